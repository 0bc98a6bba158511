%recess_turn_g869_inside.nc
[ Recess turning G869 inside a bore: a 5 mm deep recess in a 20 mm bore, cut by a    ]
[ 4 mm recessing tool that comes from the bore's axis, in levels of at most P2.       ]
HEADER
#MATERIAL  C45
FINISHED PART
N1 G0 X20 Z0
N2 G1 Z-20
N3 G1 X30
N4 G1 Z-36
N5 G1 X20
N6 G1 Z-60
MACHINING
N20 T4
N21 G97 S500 G95 F0.1 M3
N22 G0 X10 Z5
N23 G869 NS3 NE5 SB4 P2 O0.05 E0.04
N24 G0 X0 Z5
N25 M30
END
