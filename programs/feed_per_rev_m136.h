0  BEGIN PGM FEED_PER_REV_M136 MM
; M136: F in mm per spindle revolution. The slot along X runs at 0.2 mm per revolution of
; the measured spindle (every servo cycle), also while the spindle slows under the cut;
; M137 returns to mm/min.
1  BLK FORM 0.1 Z X+0 Y+0 Z-20
2  BLK FORM 0.2 X+100 Y+100 Z+0
3  TOOL DEF 1 L+50 R+5
4  TOOL CALL 1 Z S1000
5  L X+0 Y+0 Z+2 R0 FMAX M3
6  L Z-2 F200
7  L X+30 F0.2 M136
8  L Z+20 F2000 M137
9  L Z+50 FMAX M30
10 END PGM FEED_PER_REV_M136 MM
