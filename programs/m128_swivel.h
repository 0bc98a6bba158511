0  BEGIN PGM M128_SWIVEL MM
1  ; TCPM on a table-table A/C machine (machines/mill5.toml): with M128 the tool tip stays
2  ; on the programmed workpiece point while the table tilts and turns underneath it.
3  BLK FORM 0.1 Z X-50 Y-50 Z-40
4  BLK FORM 0.2 X+50 Y+50 Z+0
5  TOOL CALL 1 Z S6000
6  L Z+50 R0 FMAX M3
7  L X+20 Y+10 FMAX
8  L Z+5 FMAX M128
9  ; the tip stays at X+20 Y+10 Z+5 of the workpiece while A and C move
10 L A+30 F1500
11 L C+90
12 L A-20 C+180
13 ; a straight cut along the workpiece X axis with the table still turned
14 L X-20 F600
15 L A+0 C+0 F1500
16 L Z+50 FMAX M129
17 FUNCTION TCPM F TCP AXIS POS PATHCTRL AXIS
18 L A+15 F1500
19 L A+0
20 FUNCTION RESET TCPM
21 L Z+100 FMAX M30
22 END PGM M128_SWIVEL MM
