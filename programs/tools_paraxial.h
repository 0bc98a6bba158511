0  BEGIN PGM TOOLS_PARAXIAL MM
; TOOL DEF with length and radius, TOOL CALL using it, paraxial compensation R+/R- (the move
; lengthened or shortened by the tool radius) and the M140 retract along the tool axis.
1  BLK FORM 0.1 Z X-10 Y-10 Z-20
2  BLK FORM 0.2 X+60 Y+60 Z+0
3  TOOL DEF 5 L+60 R+4
4  TOOL CALL 5 Z S3000
5  L Z+10 R0 FMAX M3
6  L X+0 Y+0 FMAX
7  L Z-2 F300
8  L X+40 R+
9  L Y+40 R-
10 L Z+10 FMAX
11 L X+0 Y+0 Z+5 F500 M140 MB 20
12 M30
13 END PGM TOOLS_PARAXIAL MM
