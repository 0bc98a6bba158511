%groove_g860.nc
[ A V-shaped recess in the FINISHED PART contour cut by G860: plunges of a 3 mm wide ]
[ tool, each down to the contour under its width, then a finishing pass (Q0).        ]
HEADER
#MATERIAL  C45
FINISHED PART
N1 G0 X0 Z0
N2 G1 X50
N3 G1 Z-20
N4 G1 X40 Z-25
N5 G1 Z-29
N6 G1 X50 Z-34
N7 G1 Z-60
MACHINING
N10 T4
N11 G97 S500 G95 F0.06 M3
N12 G0 X54 Z5
N13 G860 NS4 NE6 P3 E0.04
N14 G0 X70 Z5
N15 M30
END
