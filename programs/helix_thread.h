0  BEGIN PGM HELIX_THREAD MM
; Internal right-hand thread milled as a helix, work direction Z+ (table in the TNC manual:
; internal, right-hand, Z+ -> DR+ with RL). Thread M40 x 1.5, 5 thread revolutions, plus an
; overrun of half a revolution at the start and at the end:
;   revolutions n     = 5 + 0.5 + 0.5       = 6
;   total height h    = P * n = 1.5 * 6     = 9 mm
;   total angle IPA   = n * 360             = 2160 deg
;   start Z           = -P * (5 + 0.5)      = -8.25 mm  (end Z = -8.25 + 9 = +0.75)
; Tool: thread mill R5. This program runs on the tool centre (R0): centre-path radius
; 20 - 5 = 15 mm about the bore axis X+0 Y+0.
1  BLK FORM 0.1 Z X-40 Y-40 Z-20
2  BLK FORM 0.2 X+40 Y+40 Z+0
3  TOOL CALL 1 Z S2000 DR+5
4  L Z+20 R0 FMAX M3
5  CC X+0 Y+0
6  L X+0 Y+0 FMAX
7  L Z-8.25 FMAX
8  LP PR+15 PA+0 R0 F300
9  CP IPA+2160 IZ+9 DR+ R0 F200
10 L X+0 Y+0 F300
11 L Z+20 FMAX M30
12 END PGM HELIX_THREAD MM
