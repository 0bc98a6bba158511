%shaft_turning.nc
[ Turning a stepped shaft, then a finishing pass along the FINISHED PART contour (G890). ]
[ X is programmed as a diameter.                                                      ]
HEADER
#MATERIAL  C45
#UNIT      METRIC
TURRET
T1 ID"FINISH-TOOL-35"
T2 ID"DRILL-D8"
BLANK
N1 G20 X60 Z100 K2
FINISHED PART
N2 G0 X0 Z0
N3 G1 X36 BR-1 [ 1 mm chamfer at the front edge ]
N4 G1 Z-20
N5 G1 X56 BR2 [ rounded shoulder edge ]
N6 G1 Z-40
MACHINING
N10 T1
N11 G26 S3000
N12 G96 S180 G95 F0.25 M4
N13 G0 X62 Z2 M8
N14 G0 X40
N15 G1 Z-20
N16 G13 X50 Z-25 R5 [ quarter circle shoulder, centre X40 Z-25 ]
N17 G1 X56
N18 G2 Xi4 Zi-2 I0 K-2 [ the same kind of corner with an incremental centre ]
N19 G1 Z-40
N195 G0 X62 Z2
N196 G0 X0
N197 G890 NS3 NE6 F0.1 [ finishing pass along the FINISHED PART contour ]
N20 G0 X62
N21 G14 Q1
N22 T2
N23 G97 S1500 M3
N24 G0 X0 Z3
N25 G71 Z-25 F0.12
N26 G14 Q0 M9
N27 M30
END
