%CYCLE_TRANSFORMS G71 *
; ISO twin of programs/cycle_transforms.h: one contour (label 1) repeated under the
; coordinate transformations G54 datum shift, G28 mirror image, G73 rotation and G72
; scaling, then all reset. G62 sets the path tolerance, G04 dwells between the parts.
N10 G30 G17 X-60 Y-60 Z-10 *
N20 G31 G90 X+60 Y+60 Z+0 *
N30 G99 T1 L+50 R+2 *
N40 T1 G17 S4000 *
N50 G62 T0.02 *
N60 G00 G40 Z+10 M03 *
N70 L1,0 *
; the same contour 25 mm further in X
N80 G54 X+25 Y+0 *
N90 L1,0 *
N100 G04 F0.5 *
; mirrored about the Y axis through the shifted datum
N110 G28 X *
N120 L1,0 *
N130 G28 *
; turned by 90 degrees and halved
N140 G73 G90 H+90 *
N150 G72 F0.5 *
N160 L1,0 *
; back to the original system
N170 G72 F1 *
N180 G73 G90 H+0 *
N190 G54 X+0 Y+0 *
N200 G00 G40 Z+50 M30 *
N210 G98 L1 *
N220 G00 G40 X+12 Y-5 *
N230 G01 Z-2 F300 *
N240 G41 X+12 Y+5 F500 *
N250 X+20 *
N260 I+20 J+10 *
N270 G03 X+25 Y+10 *
N280 G01 Y+15 *
N290 X+5 *
N300 Y+5 *
N310 X+12 *
N320 G40 X+12 Y-5 *
N330 G00 Z+10 *
N340 G98 L0 *
N99999999 %CYCLE_TRANSFORMS G71 *
