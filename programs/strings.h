0  BEGIN PGM STRINGS MM
; QS string parameters: a text is taken apart with INSTR, SUBSTR, STRLEN and TONUMB, checked
; with STRCOMP, and the label of the subprogram to run is built with || and called by name.
; Mills a square of the size written in the text, with R5 roundings.
1  BLK FORM 0.1 Z X-10 Y-10 Z-20
2  BLK FORM 0.2 X+60 Y+60 Z+0
3  TOOL CALL 1 Z S3000
4  DECLARE STRING QS1 = "SIZE=40;SHAPE=square"
5  QS2 = ";"
6  Q1 = INSTR( SRC_QS1 SEA_QS2 BEG0 ) ; position of ';' (from 0)
7  Q2 = Q1 - 5
8  QS3 = SUBSTR( SRC_QS1 BEG5 LENQ2 ) ; "40"
9  Q3 = TONUMB( SRC_QS3 )
10 Q4 = Q1 + 7
11 Q5 = STRLEN( SRC_QS1 ) - Q4
12 QS4 = SUBSTR( SRC_QS1 BEGQ4 LENQ5 ) ; "square"
13 QS5 = "square"
14 Q6 = STRCOMP( SRC_QS4 SEA_QS5 )
15 FN 10: IF +Q6 NE +0 GOTO LBL "unknown"
16 STRING FORMULA QS6 = "mill_" || QS4
17 QS7 = "side " || TOCHAR( DAT+Q3 DECIMALS1 ) || " mm"
18 L Z+10 R0 FMAX M3
19 CALL LBL QS6
20 L Z+10 FMAX M30
21 LBL "mill_square"
22 L X+0 Y+0 FMAX
23 L Z-2 F200
24 L X+Q3 F600
25 RND R5
26 L Y+Q3
27 RND R5
28 L X+0
29 L Y+0
30 L Z+10 FMAX
31 LBL 0
32 LBL "unknown"
33 FN 14: ERROR = 1
34 END PGM STRINGS MM
