0  BEGIN PGM RECTANGLE_RL MM
; The rectangle of rectangle.h programmed on the part contour: the tool (R5, from DR+5 while
; no tool table is configured) runs outside it with RL, clockwise.
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+100 Y+60 Z+0
3  TOOL CALL 1 Z S3000 DR+5
4  L Z+50 R0 FMAX M3
5  L X-20 Y+10 FMAX
6  L Z-5 F300 M8
7  L X+0 Y+10 RL F600
8  L Y+50
9  CR X+10 Y+60 R+10 DR-
10 L X+80
11 CT X+100 Y+40
12 L Y+10
13 CC X+90 Y+10
14 C X+90 Y+0 DR-
15 L X+10
16 CR X+0 Y+10 R+10 DR-
17 L X-20 Y+10 R0
18 L Z+50 FMAX M9
19 L X-10 Y+10 FMAX M30
20 END PGM RECTANGLE_RL MM
