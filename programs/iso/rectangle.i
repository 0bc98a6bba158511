%RECTANGLE G71 *
; ISO twin of programs/rectangle.h: the same contour, block for block.
N10 G30 G17 X+0 Y+0 Z-20 *
N20 G31 G90 X+100 Y+60 Z+0 *
N30 T1 G17 S3000 *
N40 G00 G40 G90 Z+50 M03 *
N50 X-10 Y+10 *
N60 G01 Z-5 F300 M08 *
N70 X+0 Y+10 F600 *
N80 Y+50 *
N90 G02 X+10 Y+60 R+10 * ; rounded corner, centre X+10 Y+50
N100 G01 X+80 *
N110 G06 X+100 Y+40 * ; tangential arc, radius 20 about X+80 Y+40
N120 G01 Y+10 *
N130 I+90 J+10 * ; the pole alone
N140 G02 X+90 Y+0 * ; quarter circle about the pole
N150 G01 X+10 *
N160 G02 X+0 Y+10 R+10 *
N170 G00 Z+50 M09 *
N180 X-10 Y+10 M30 *
N99999999 %RECTANGLE G71 *
