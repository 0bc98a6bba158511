0  BEGIN PGM CALL_PGM_SQUARE MM
; Called by call_pgm.h: a 20 mm square with its corner at X+Q1 Y+Q2.
1  L X+Q1 Y+Q2 FMAX
2  L Z-1 F200
3  L IX+20 F400
4  L IY+20
5  L IX-20
6  L IY-20
7  L Z+10 FMAX
8  END PGM CALL_PGM_SQUARE MM
