0 BEGIN PGM A MM
1 L X+1 F100
2 CALL PGM call_pgm_recursive.h
3 END PGM A MM
