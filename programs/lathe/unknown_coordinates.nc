%unknown_coordinates.nc
[ FINISHED PART elements with unknown coordinates: N3 is a 150° cone whose end the   ]
[ control finds where it meets the cylinder N4 (diameter 60, A180); N5 gives only its ]
[ Z and its angle, X follows. G890 finishes the solved contour.                       ]
HEADER
#MATERIAL  C45
FINISHED PART
N1 G0 X0 Z0
N2 G1 X20
N3 G1 X? Z? A150
N4 G1 X60 Z-40 A180
N5 G1 X? Z-60 A165
N6 G1 X80
MACHINING
N10 T1
N11 G96 S200 G95 F0.1 M4
N12 G0 X82 Z2
N13 G890
N14 G0 X90 Z5
N15 M30
END
