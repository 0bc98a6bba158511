%HELIX_THREAD G71 *
; ISO version of programs/helix_thread.h: internal right-hand thread M40 x 1.5 milled as a
; helix (Z+ work direction, DR+), 6 revolutions = 2160 degrees, 9 mm rise, tool centre path
; radius 15 mm about the bore axis X+0 Y+0 (the pole I J).
N10 G30 G17 X-40 Y-40 Z-20 *
N20 G31 G90 X+40 Y+40 Z+0 *
N30 T1 G17 S2000 DR+5 *
N40 G00 G40 G90 Z+20 M03 *
N50 I+0 J+0 *
N60 G00 X+0 Y+0 *
N70 Z-8.25 *
N80 G11 G40 R+15 H+0 F300 *
N90 G91 *
N100 G13 H+2160 Z+9 F200 * ; incremental: the helix turns 2160 degrees and rises 9 mm
N110 G90 *
N120 G01 X+0 Y+0 F300 *
N130 G00 Z+20 M30 *
N99999999 %HELIX_THREAD G71 *
