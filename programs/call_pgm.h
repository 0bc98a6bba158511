0  BEGIN PGM CALL_PGM MM
; CALL PGM: the called program (path relative to this file) shares the Q parameters and
; returns at its END PGM.
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+100 Y+100 Z+0
3  TOOL CALL 1 Z S3000
4  L Z+10 R0 FMAX M3
5  Q1 = 20
6  Q2 = 20
7  CALL PGM call_pgm_square.h
8  Q1 = 60
9  CALL PGM call_pgm_square.h
10 L Z+10 FMAX M30
11 END PGM CALL_PGM MM
