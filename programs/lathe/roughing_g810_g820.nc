%roughing_g810_g820.nc
[ Roughing a bar of diameter 60 along the FINISHED PART contour: G820 faces the shoulder ]
[ region in cuts parallel to X, G810 turns in cuts parallel to Z, G890 finishes.         ]
HEADER
#MATERIAL  C45
BLANK
N1 G20 X60 Z80 K1
FINISHED PART
N2 G0 X0 Z0
N3 G1 X40
N4 G1 Z-30
N5 G1 X50 Z-40
N6 G1 Z-60
N7 G1 X60
MACHINING
N10 T1
N11 G96 S200 G95 F0.3 M4
N12 G0 X64 Z3
N13 G810 P4 F0.3
N14 G820 P5 I1 K0.5 F0.25
N15 G890 F0.1
N16 G0 X70 Z5
N17 M30
END
