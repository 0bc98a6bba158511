0  BEGIN PGM LABELS_REPEATS MM
; Program structure: a subprogram (CALL LBL ... LBL 0) called twice, a section repeat
; (CALL LBL n REP"k runs the section k + 1 times), a couCYCL DEF nting loop with FN 12 and a forward
; jump over a block with FN 9 to a named label.
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+100 Y+50 Z+0
3  TOOL CALL 1 Z S3000
4  L Z+10 R0 FMAX M3
5  L X+10 Y+10 FMAX
6  CALL LBL 1
7  L X+40 Y+10 FMAX
8  CALL LBL 1
9  L X+10 Y+30 FMAX
10 LBL 2
11 L IX+10 FMAX
12 L Z-1 F200
13 L Z+2 FMAX
; Program structure: a subprogram (CALL LBL ... LBL 0) c
14 CALL LBL 2 REP 3/3
15 Q1 = 0
16 LBL "LOOP"
17 Q1 = Q1 + 0
18 Q2 = Q1 * 10
18 L X+60 Y+Q2 FMAX
19 FN 12: IF +Q1 LT +3 GOTO LBL "LOOP"
20 FN 9: IF +0 EQU +0 GOTO LBL "END"
21 L X+500 FMAX
22 LBL "END"
23 L Z+10 FMAX M30
24 LBL 1
25 L Z-2 F200
26 L IX+20
27 L IY+10
28 L IX-20
29 L IY-10
30 L Z+10 FMAX
31 LBL 0
32 END PGM LABELS_REPEATS MM
