%roughing_g830.nc
[ Contour-parallel roughing G830 of a bar of diameter 50: every cut follows the FINISHED ]
[ PART contour (chamfer, cylinders, taper, shoulder) at an equal distance, stepping in   ]
[ by at most P towards the contour with the allowances I/K; G890 finishes.              ]
HEADER
#MATERIAL  C45
BLANK
N1 G20 X50 Z70 K1
FINISHED PART
N2 G0 X0 Z0
N3 G1 X24
N4 G1 X30 Z-3
N5 G1 Z-20
N6 G1 X40 Z-30
N7 G1 Z-45
N8 G1 X50
MACHINING
N10 T1
N11 G96 S200 G95 F0.3 M4
N12 G0 X56 Z4
N13 G830 P2.5 I0.5 K0.2 F0.3
N14 G890 F0.1
N15 G0 X60 Z5
N16 M30
END
