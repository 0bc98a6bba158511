%recess_turn_g869_face.nc
[ Axial recess turning G869: a 6 mm deep ring recess in the front face, cut by a 3 mm ]
[ recessing tool plunging along -Z in levels of at most P2.5, turning along X.        ]
HEADER
#MATERIAL  C45
FINISHED PART
N1 G0 X0 Z0
N2 G1 X20
N3 G1 Z-6
N4 G1 X36
N5 G1 Z0
N6 G1 X60
N7 G1 Z-30
MACHINING
N20 T4
N21 G97 S500 G95 F0.1 M3
N22 G0 X40 Z5
N23 G869 NS3 NE5 SB3 P2.5 O0.05 E0.04
N24 G0 X70 Z5
N25 M30
END
