0  BEGIN PGM POLAR_PATHS MM
; Polar coordinates: LP and CP about CC, CC alone (the last position becomes the pole),
; CC incremental, CTP (tangential arc to a polar end point) and an arc in the Z/X plane
; selected by the axes named in CC (Z/X: angles from +Z towards +X).
1  BLK FORM 0.1 Z X-60 Y-60 Z-20
2  BLK FORM 0.2 X+60 Y+60 Z+0
3  TOOL CALL 1 Z S3000
4  L Z+10 R0 FMAX M3
5  CC X+0 Y+0
6  LP PR+40 PA+0 FMAX
7  L Z-2 F200
8  CP PA+90 DR+ F500
9  LP PR+20 PA+90
10 CTP PR+30 PA+180
11 L IX+0 IY-10
12 CC
13 LP PR+10 PA-90
14 CC IX+10 IY+0
15 CP IPA-180 DR-
16 L Z+10 FMAX
17 L X+20 Y+0 Z+5 FMAX
18 CC Z+0 X+20
19 C Z-5 X+20 DR+ F300
20 L Z+10 FMAX
21 M30
22 END PGM POLAR_PATHS MM
