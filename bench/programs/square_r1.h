0  BEGIN PGM SQUARE_R1 MM
; A 50 x 50 mm square with 1 mm corner radii (X-25..+25, Y0..50), started mid-edge, F6000.
1  L X+24 F6000
2  CR X+25 Y+1 R+1 DR+
3  L Y+49
4  CR X+24 Y+50 R+1 DR+
5  L X-24
6  CR X-25 Y+49 R+1 DR+
7  L Y+1
8  CR X-24 Y+0 R+1 DR+
9  L X+0
10 END PGM SQUARE_R1 MM
