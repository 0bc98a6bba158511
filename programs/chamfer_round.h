0  BEGIN PGM CHAMFER_ROUND MM
; CHF and RND between straight lines: a 60 x 40 rectangle with a 5 mm chamfer at one corner
; and R8 roundings at two others, milled on the tool centre.
1  BLK FORM 0.1 Z X-10 Y-10 Z-20
2  BLK FORM 0.2 X+70 Y+50 Z+0
3  TOOL CALL 1 Z S3000
4  L Z+10 R0 FMAX M3
5  L X+0 Y+0 FMAX
6  L Z-2 F200
7  L X+60 Y+0 F600
8  CHF 5
9  L X+60 Y+40
10 RND R8 F300
11 L X+0 Y+40
12 RND R8
13 L X+0 Y+0
14 L Z+10 FMAX M30
15 END PGM CHAMFER_ROUND MM
