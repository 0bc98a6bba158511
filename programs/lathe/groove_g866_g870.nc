%groove_g866_g870.nc
[ Two G22 recesses on a shaft of diameter 40: G866 cuts the 10 mm wide one with a  ]
[ 4 mm grooving tool in three plunges, G870 the 4 mm wide one in a single plunge,    ]
[ G866 with I0.2 leaves 0.2 mm and finishes walls and floor. G890 finishes the part. ]
HEADER
#MATERIAL  C45
BLANK
N1 G20 X42 Z80 K1
FINISHED PART
N2 G0 X0 Z0
N3 G1 X40
N4 G1 Z-50
N5 G22 Z-20 I30 K-30
N6 G1 X60
N7 G1 Z-70
N8 G22 Z-56 Ii-8 Ki-4
MACHINING
N10 T3
N11 G97 S600 G95 F0.05 M3
N12 G0 X64 Z5
N13 G866 NS5 P4 E0.5
N14 G870 NS8 P4
N15 G866 NS5 P4 I0.2 F0.04
N16 G0 X70 Z5
N17 M30
END
