%thread_g33.nc
[ An M20 x 1.5 external thread in four G33 passes, each geared to the measured spindle ]
[ angle and started at the same spindle angle C, so every pass deepens the same groove. ]
HEADER
#MATERIAL  C45
#UNIT      METRIC
TURRET
T3 ID"THREAD-EXT-60"
MACHINING
N10 T3
N11 G97 S800 G95 M3
N12 G0 X24 Z6
N20 G0 X19.6
N21 G33 X19.6 Z-30 F1.5 B4 P3 C30
N22 G0 X24
N23 G0 Z6
N30 G0 X19.2
N31 G33 X19.2 Z-30 F1.5 B4 P3 C30
N32 G0 X24
N33 G0 Z6
N40 G0 X18.8
N41 G33 X18.8 Z-30 F1.5 B4 P3 C30
N42 G0 X24
N43 G0 Z6
N50 G0 X18.4
N51 G33 X18.4 Z-30 F1.5 B4 P3 C30
N52 G0 X24
N53 G14 Q0
N54 M30
END
