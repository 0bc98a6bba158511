0  BEGIN PGM PLANE_CONTOUR MM
1  ; Side milling on a face inclined 30 degrees about X (table-table A/C machine,
2  ; machines/mill5.toml): the outline of a 40 x 30 boss with rounded corners, cut with
3  ; radius compensation RR in the tilted plane, approached with APPR LCT and left with
4  ; DEP LCT. The compensation runs in the tilted plane's own coordinates.
5  BLK FORM 0.1 Z X-50 Y-50 Z-40
6  BLK FORM 0.2 X+50 Y+50 Z+0
7  TOOL CALL 1 Z S6000 DR+4
8  PLANE RESET STAY
9  L Z+100 R0 FMAX M3
10 ; tilt: table A turns to +30 (Q120), the tool tip keeps its place
11 PLANE SPATIAL SPA+30 SPB+0 SPC+0 MOVE DIST+0 F2000 SEQ+ COORD ROT
12 ; from here X Y Z are in the tilted system
13 L X-40 Y-40 FMAX
14 L Z+5 FMAX
15 L Z-3 F300 M8
16 APPR LCT X-20 Y-15 R8 RR F600
17 L X+20 Y-15
18 RND R5
19 L X+20 Y+15
20 RND R5
21 L X-20 Y+15
22 RND R5
23 L X-20 Y-15
24 DEP LCT X-40 Y-30 R8 F600
25 L Z+50 FMAX M9
26 ; untilt: A and C turn back to 0, the tool tip held
27 PLANE RESET MOVE F2000
28 L Z+100 FMAX M30
29 END PGM PLANE_CONTOUR MM
