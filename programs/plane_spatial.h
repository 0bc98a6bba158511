0  BEGIN PGM PLANE_SPATIAL MM
1  ; Tilted working plane on a table-table A/C machine (machines/mill5.toml):
2  ; a pocket outline on a face sloping 30 degrees about X, then back to the untilted plane.
3  BLK FORM 0.1 Z X-50 Y-50 Z-40
4  BLK FORM 0.2 X+50 Y+50 Z+0
5  TOOL CALL 1 Z S6000
6  PLANE RESET STAY
7  L Z+100 R0 FMAX M3
8  ; tilt: table A turns to +30 (Q120), C stays 0 (Q122); the tool tip keeps its place
9  PLANE SPATIAL SPA+30 SPB+0 SPC+0 MOVE DIST+0 F2000 SEQ+ COORD ROT
10 ; from here X Y Z are in the tilted system
11 L X-20 Y-15 FMAX
12 L Z+5 FMAX
13 L Z-3 F300 M8
14 L X+20 F800
15 CR X+25 Y-10 R+5 DR+
16 L Y+10
17 CR X+20 Y+15 R+5 DR+
18 L X-20
19 CC X-20 Y+10
20 C X-25 Y+10 DR+
21 L Y-15
22 L X-20
23 L Z+50 FMAX M9
24 ; untilt: A and C turn back to 0, the tool tip held
25 PLANE RESET MOVE F2000
26 L Z+100 FMAX M30
27 END PGM PLANE_SPATIAL MM
