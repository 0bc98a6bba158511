0  BEGIN PGM SQUARE_R10 MM
; LinuxCNC comparison: a 1 mm plunge at F600, a 50 x 50 mm square with 10 mm corner arcs at
; F3000 (X-25..+25, Y0..50, started mid-edge), then a rapid retract.
1  L Z-1 F600
2  L X+15 F3000
3  CR X+25 Y+10 R+10 DR+
4  L Y+40
5  CR X+15 Y+50 R+10 DR+
6  L X-15
7  CR X-25 Y+40 R+10 DR+
8  L Y+10
9  CR X-15 Y+0 R+10 DR+
10 L X+0
11 L Z+0 FMAX
12 END PGM SQUARE_R10 MM
