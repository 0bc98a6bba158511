%CYCLE_DRILLING G71 *
; ISO twin of programs/cycle_drilling.h (without its PATTERN DEF part): drilling cycle
; G200 called by M99 after a positioning block, by G79 after positioning in the plane and
; then down the tool axis (what CYCL CALL POS does), and by the Cartesian point pattern
; G221, which calls the last defined cycle at its points as soon as it is defined.
; The parameters of G200 stand on lines of their own; the last one carries the block end.
N10 G30 G17 X+0 Y+0 Z-20 *
N20 G31 G90 X+100 Y+100 Z+0 *
N30 G99 T1 L+60 R+2.5 *
N40 T1 G17 S3000 F200 *
N50 G00 G40 Z+20 M03 *
N60 G200 DRILLING
    Q200=+2    ;SET-UP CLEARANCE
    Q201=-10   ;DEPTH
    Q206=+150  ;FEED RATE FOR PLNGNG
    Q202=+5    ;PLUNGING DEPTH
    Q210=+0    ;DWELL TIME AT TOP
    Q203=+0    ;SURFACE COORDINATE
    Q204=+20   ;2ND SET-UP CLEARANCE
    Q211=+0.2  ;DWELL TIME AT DEPTH *
N70 G00 G40 X+10 Y+10 M99 *
N80 X+30 Y+10 *
N90 Z+0 *
N100 G79 *
; G221 written with `~` continuation lines
N110 G221 CARTESIAN PATTERN ~
    Q225=+10   ;STARTNG PNT 1ST AXIS ~
    Q226=+80   ;STARTNG PNT 2ND AXIS ~
    Q237=+10   ;SPACING IN 1ST AXIS ~
    Q238=+8    ;SPACING IN 2ND AXIS ~
    Q242=+3    ;NUMBER OF COLUMNS ~
    Q243=+2    ;NUMBER OF LINES ~
    Q224=+0    ;ANGLE OF ROTATION ~
    Q200=+2    ;SET-UP CLEARANCE ~
    Q203=+0    ;SURFACE COORDINATE ~
    Q204=+20   ;2ND SET-UP CLEARANCE ~
    Q301=+1    ;MOVE TO CLEARANCE *
N120 G00 G40 Z+50 M30 *
N99999999 %CYCLE_DRILLING G71 *
