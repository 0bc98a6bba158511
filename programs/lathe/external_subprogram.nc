%external_subprogram.nc
[ The grooves of subprogram_grooves.nc, with the subprogram in groove.ncs next to this ]
[ file: L"groove" finds no SUBPROGRAM "groove" here and runs the external one.         ]
MACHINING
N1 T2
N2 G97 S800 G95 F0.05 M3
N3 G0 X62 Z2
N4 #g1 = -10
N5 L"groove" LA50 LB8 Q3
N6 L"groove" LA44 LB0
N7 G0 X62 Z2
N8 G14 Q0
N9 M30
END
