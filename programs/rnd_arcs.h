0  BEGIN PGM RND_ARCS MM
; RND next to arcs: roundings between a line and an arc, two arcs, and an arc and a line.
; Each rounding arc is tangent to both neighbours, which end at the tangent points.
1  BLK FORM 0.1 Z X-10 Y-40 Z-20
2  BLK FORM 0.2 X+100 Y+30 Z+0
3  TOOL CALL 1 Z S3000
4  L Z+10 R0 FMAX M3
5  L X+0 Y+0 FMAX
6  L Z-2 F200
7  L X+30 Y+0 F600
8  RND R4
9  CC X+50 Y+0
10 C X+70 Y+0 DR-
11 RND R4
12 CC X+70 Y-20
13 C X+50 Y-20 DR+
14 RND R4 F300
15 L X+30 Y-20
16 L X+30 Y+0
17 L Z+10 FMAX M30
18 END PGM RND_ARCS MM
