%recess_turn_g869_offset.nc
[ Recess turning G869 with the offset width B: every pass back to the NS end that      ]
[ turns into a plunge stops short of it by B more than the one before (at most 0.8 of  ]
[ the cutting width SB), and one plunge at the NS end clears what they left; on the    ]
[ recess with sloped walls the next level's stretch starts further in.                 ]
HEADER
#MATERIAL  C45
FINISHED PART
N1 G0 X0 Z0
N2 G1 X50
N3 G1 Z-60
N4 G22 Z-20 I30 K-40
N5 G1 X60
N6 G1 Z-70
N7 G1 X44 Z-74
N8 G1 Z-84
N9 G1 X60 Z-88
N10 G1 Z-100
MACHINING
N20 T4
N21 G97 S500 G95 F0.1 M3
N22 G0 X54 Z5
N23 G869 NS4 SB4 P2 B2 O0.05 E0.04
N24 G0 X64 Z-65
N25 G869 NS7 NE9 SB3 P3 I1 K0.5 B1
N26 G0 X70 Z5
N27 M30
END
