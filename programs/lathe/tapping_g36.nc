%tapping_g36.nc
[ G36 on the turning axis with the work turning: an M8 x 1.25 thread tapped from Z2 to ]
[ Z-12, geared to the main spindle's measured angle in, through the reversal and out. ]
HEADER
#MATERIAL  C45
#UNIT      METRIC
TURRET
T5 ID"TAP-M8"
MACHINING
N10 T5
N11 G97 S400 G95 M3
N12 G0 X0 Z5
N13 G36 ZS2 ZE-12 F1.25
N14 G0 Z20
N15 M30
END
