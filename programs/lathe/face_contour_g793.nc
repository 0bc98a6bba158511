%face_contour_g793.nc
[ G793: a closed free contour on the face (a slot 20 mm long, 10 mm wide, with round ]
[ ends) milled 4 mm deep from ZS1 to ZE-3 in infeeds of 2 mm, the spindle held at C30. ]
[ The contour is written in the face's Cartesian system XK/YK and ends with G80.       ]
MACHINING
N1 T3 G197 S2000 G195 F0.05 M103
N2 M14
N3 G110 C30
N4 G0 X80 Z5
N5 G793 ZS1 ZE-3 P2 F0.04
N6 G0 XK-10 YK0
N7 G1 XK10
N8 G3 XK10 YK10 I10 J5
N9 G1 XK-10
N10 G3 XK-10 YK0 R5
N11 G80
N12 G0 Z5 M15
N13 M30
END
