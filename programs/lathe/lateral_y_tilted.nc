%lateral_y_tilted.nc
[ A tilted LATERAL_Y plane on a B-axis lathe: the manual's SURFACE_Y example in its section,]
[ then four holes drilled on the face by a G745 pattern that drills by itself (ZE).        ]
HEADER
#MACHINE built-in lathe X Z C Y B
TURRET
T3 ID"DRILL-D6"
BLANK
N1 G20 X120 Z100 K2
FINISHED PART
N2 G0 X0 Z0
N3 G1 X118
N4 G1 Z-80
LATERAL_Y
SURFACE_Y X118 C0 B130 I59 K0
N5 G0 Y-10 Z-20
N6 G1 Y10
MACHINING
N10 T3 G197 S2000 G195 F0.05 M103
N11 M14
N12 G0 X120 Z5
N13 G745 X0 C0 K80 A45 Wi90 Q4 ZS2 ZE-12
N14 M15
N15 M30
END
