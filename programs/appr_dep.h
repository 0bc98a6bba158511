0  BEGIN PGM APPR_DEP MM
; Approach on a line and a tangential arc (APPR LCT, radius compensation RR switched on),
; a contour, then a tangential departure (DEP LT), as in the TNC manual's example.
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+60 Y+60 Z+0
3  TOOL CALL 1 Z S3000 DR+0
4  L Z+10 R0 FMAX M3
5  L X+40 Y+10 R0 FMAX
6  APPR LCT X+10 Y+20 Z-10 R10 RR F100
7  L X+20 Y+35
8  L X+40 Y+35
9  L Y+20
10 DEP LT LEN12.5 F100
11 L Z+100 FMAX M30
12 END PGM APPR_DEP MM
