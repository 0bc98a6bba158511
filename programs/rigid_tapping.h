0  BEGIN PGM RIGID_TAPPING MM
; Rigid tapping geared to the measured spindle angle: cycle 207 taps an M8 x 1.25
; right-hand thread in one stroke and retracts twice as fast (Q403); cycle 209 taps an
; M10 x 1.5 with chip breaking (infeeds of 4 mm, backing off 0.5 mm). The tool axis
; follows pitch x spindle angle in, through each reversal and out.
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+100 Y+100 Z+0
3  TOOL DEF 5 L+80 R+4
4  TOOL DEF 6 L+80 R+5
5  TOOL CALL 5 Z S800
6  L Z+20 R0 FMAX M3
7  CYCL DEF 207 RIGID TAPPING ~
    Q200=+2    ;SET-UP CLEARANCE ~
    Q201=-12   ;DEPTH ~
    Q239=+1.25 ;THREAD PITCH ~
    Q203=+0    ;SURFACE COORDINATE ~
    Q204=+10   ;2ND SET-UP CLEARANCE ~
    Q403=+2    ;FACTOR FOR SPEED
8  L X+30 Y+30 R0 FMAX M99
9  TOOL CALL 6 Z S600
10 L Z+20 R0 FMAX M3
11 CYCL DEF 209 TAPPING W/ CHIP BRKG ~
    Q200=+2    ;SET-UP CLEARANCE ~
    Q201=-10   ;DEPTH ~
    Q239=+1.5  ;THREAD PITCH ~
    Q203=+0    ;SURFACE COORDINATE ~
    Q204=+10   ;2ND SET-UP CLEARANCE ~
    Q257=+4    ;DEPTH FOR CHIP BRKNG ~
    Q256=+0.5  ;DIST FOR CHIP BRKNG ~
    Q336=+0    ;ANGLE OF SPINDLE ~
    Q403=+1    ;FACTOR FOR SPEED
12 L X+60 Y+30 R0 FMAX M99
13 L Z+50 R0 FMAX M30
14 END PGM RIGID_TAPPING MM
