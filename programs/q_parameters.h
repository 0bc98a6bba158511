0  BEGIN PGM Q_PARAMETERS MM
; Q parameters: FN 0-13, formulas with precedence and functions (angles in degrees), signed
; parameter words (X-Q1, FQ5), FN 18 SYSREAD of the current position and FN 15 output.
1  BLK FORM 0.1 Z X-50 Y-50 Z-20
2  BLK FORM 0.2 X+50 Y+50 Z+0
3  TOOL CALL 1 Z S3000
4  FN 0: Q1 = +30
5  FN 1: Q2 = +Q1 + +10
6  FN 4: Q3 = +Q2 DIV +2
7  FN 8: Q4 = +3 LEN +4
8  FN 13: Q6 = +1 ANG +1
9  Q5 = 600 + 20 * 2 ^ 2
10 Q7 = Q1 * COS Q6 + SQRT ( SQ 3 + SQ 4 ) - Q3 % 7
11 L Z+10 R0 FMAX M3
12 L X-Q1 Y+Q3 FMAX
13 L Z-1 FQ5
14 L X+Q7 Y-Q4
15 FN 18: SYSREAD Q10 = ID270 NR1 IDX1
16 FN 18: SYSREAD Q11 = ID270 NR1 IDX2
17 FN 15: PRINT Q10/Q11
18 L Z+10 FMAX M30
19 END PGM Q_PARAMETERS MM
