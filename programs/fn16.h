0  BEGIN PGM FN16 MM
; FN 16 F-PRINT: fills the format file fn16.A with parameter values and writes the result to
; fn16_log.txt next to this program (a check run writes nothing).
1  TOOL CALL 1 Z S2000
2  Q1 = 12.5
3  Q2 = 30
4  QS1 = "PART-7"
5  L Z+10 R0 FMAX M3
6  L X+Q1 Y+Q2 FMAX
7  FN 18: SYSREAD Q10 = ID270 NR1 IDX1
8  FN 16: F-PRINT fn16.A / fn16_log.txt
9  L Z+20 FMAX M30
10 END PGM FN16 MM
