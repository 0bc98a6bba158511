0  BEGIN PGM CYCLE_TRANSFORMS MM
; One contour (LBL 1: a 20 x 10 rectangle with a rounded corner, milled with RL) repeated
; under the coordinate transformation cycles: datum shift 7, mirror image 8 (one axis: the
; arc turns the other way and RL becomes RR), rotation 10, scaling 11, then all reset.
; Cycle 32 sets the path tolerance, cycle 9 dwells between the parts.
1  BLK FORM 0.1 Z X-60 Y-60 Z-10
2  BLK FORM 0.2 X+60 Y+60 Z+0
3  TOOL DEF 1 L+50 R+2
4  TOOL CALL 1 Z S4000
5  CYCL DEF 32.0 TOLERANCE
6  CYCL DEF 32.1 T0.02
7  L Z+10 R0 FMAX M3
8  CALL LBL 1
; the same contour 25 mm further in X
9  CYCL DEF 7.0 DATUM SHIFT
10 CYCL DEF 7.1 X+25
11 CYCL DEF 7.2 Y+0
12 CALL LBL 1
13 CYCL DEF 9.0 DWELL TIME
14 CYCL DEF 9.1 DWELL 0.5
; mirrored about the Y axis through the shifted datum
15 CYCL DEF 8.0 MIRROR IMAGE
16 CYCL DEF 8.1 X
17 CALL LBL 1
18 CYCL DEF 8.0 MIRROR IMAGE
19 CYCL DEF 8.1
; turned by 90 degrees and halved
20 CYCL DEF 10.0 ROTATION
21 CYCL DEF 10.1 ROT+90
22 CYCL DEF 11.0 SCALING
23 CYCL DEF 11.1 SCL 0.5
24 CALL LBL 1
; back to the original system
25 CYCL DEF 11.0 SCALING
26 CYCL DEF 11.1 SCL 1
27 CYCL DEF 10.0 ROTATION
28 CYCL DEF 10.1 ROT+0
29 CYCL DEF 7.0 DATUM SHIFT
30 CYCL DEF 7.1 X+0
31 CYCL DEF 7.2 Y+0
32 L Z+50 R0 FMAX M30
33 LBL 1
34 L X+12 Y-5 R0 FMAX
35 L Z-2 F300
36 L X+12 Y+5 RL F500
37 L X+20
38 CC X+20 Y+10
39 C X+25 Y+10 DR+
40 L Y+15
41 L X+5
42 L Y+5
43 L X+12
44 L X+12 Y-5 R0
45 L Z+10 FMAX
46 LBL 0
47 END PGM CYCLE_TRANSFORMS MM
