%patterns_linear_lateral.nc
[ Linear hole patterns on the face (G743) and hole patterns on the lateral surface    ]
[ (G744 in a row along Z, G746 on a circle of the unrolled surface), drilled with the ]
[ driven tool and the C axis.                                                          ]
MACHINING
N1 T5 G197 S1500 G195 F0.06 M103
N2 M14
N3 G0 X80 Z3
N4 G743 XK-15 YK-15 I15 J15 Q4 ZS1 ZE-6 [ four holes on a diagonal, drilled by G743 itself ]
N5 G0 X90 Z-10
N6 G744 Z-10 C0 Ki-12 Q3 XS82 [ three holes in a row along Z … ]
N7 G74 XE60 P4 I1 J2 [ … deep-hole drilled to diameter 60 ]
N8 G746 X80 Z-25 C90 K16 A0 Q6 XS82 XE70 [ six holes on a circle around Z-25, C90 ]
N9 G0 X100 Z5 M15
N10 M30
END
