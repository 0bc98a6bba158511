%thread_g31.nc
[ An M20 x 1.5 external thread with the thread cycle G31: depth 0.9 mm, at most 0.4 mm ]
[ a cut with the remaining cut distributed (V2), the infeed alternating between the     ]
[ flanks at 30 degrees (H3 A30), one air cut (Q1), run-in 4 mm and run-out 3 mm, all    ]
[ passes starting at the spindle angle C30. Every pass is geared to the measured spindle. ]
HEADER
#MATERIAL  C45
#UNIT      METRIC
TURRET
T3 ID"THREAD-EXT-60"
MACHINING
N10 T3
N11 G97 S800 G95 M3
N12 G0 X24 Z6
N20 G31 X20 Z-24 F1.5 U-0.9 I0.4 V2 H3 A30 Q1 B4 P3 C30
N30 G14 Q0
N40 M30
END
