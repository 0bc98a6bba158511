0  BEGIN PGM M116_ROTARY_FEED MM
1  ; Feeds of the rotary table on the table-table A/C machine (machines/mill5.toml).
2  ; M116: F on the table axes is the tool point's speed over the workpiece, from the tool
3  ; point's distance to the turning axes at the start of each block; M117 ends it.
4  TOOL CALL 1 Z S6000
5  L X+50 Y+0 Z+10 A+0 C+0 R0 FMAX M3
6  ; 50 mm from the C axis: a quarter turn is a 78.5 mm arc, 4.7 s at 1000 mm/min
7  L C+90 F1000 M116
8  ; linear and rotary together: 30 mm in X and a quarter turn, one tool point path
9  L X+80 C+180
10 ; M117: 1000 degrees/min again, 5.4 s for the quarter turn
11 L C+90 M117
12 L X+50 C+0 FMAX
13 ; TCPM with the feed of its compensating moves: the cut at 3000 mm/min, the linear
14 ; axes' moves that hold the tip while the table turns within 500 mm/min
15 L X+20 Y+10 Z+5 F3000 M128 F500
16 L A+20 C+30 F30000
17 L A+0 C+0
18 M129
19 ; FUNCTION TCPM F CONT: F is the contouring feed of X and C together (mm and degrees)
20 FUNCTION TCPM F CONT AXIS POS PATHCTRL AXIS REFPNT TIP-TIP
21 L X+50 C+40 F600
22 L X+20 C+0
23 FUNCTION RESET TCPM
24 L Z+100 FMAX M30
25 END PGM M116_ROTARY_FEED MM
