%feed_per_rev.nc
[ Longitudinal turning at 0.3 mm per revolution (G95) and 1000 rpm: the feed follows the ]
[ measured spindle speed every servo cycle, so the tool advances 0.3 mm per revolution ]
[ also while the spindle slows under the cut. ]
HEADER
#MATERIAL  C45
#UNIT      METRIC
TURRET
T1 ID"ROUGH-80"
MACHINING
N10 T1
N11 G97 S1000 G95 M3
N12 G0 X40 Z2
N13 G1 Z-40 F0.3
N14 G0 X44
N15 G0 Z2
N16 M30
END
