%groove_g860_face.nc
[ A recess in the front face cut axially by G860: plunges of a 4 mm wide tool along -Z, ]
[ each down to the contour under its width, then a finishing pass (Q0).                  ]
HEADER
#MATERIAL  C45
FINISHED PART
N1 G0 X0 Z0
N2 G1 X30
N3 G1 X32 Z-6
N4 G1 X52
N5 G1 X54 Z0
N6 G1 X60
N7 G1 Z-40
MACHINING
N10 T4
N11 G97 S500 G95 F0.06 M3
N12 G0 X60 Z2
N13 G860 NS3 NE5 P4 E0.04
N14 G0 X70 Z5
N15 M30
END
