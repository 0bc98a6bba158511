%subprogram_grooves.nc
[ Grooves cut by a local subprogram: LA is the groove diameter, LB the step to the next  ]
[ groove; Q repeats the call. The global #g1 carries the Z position from call to call.   ]
MACHINING
N1 T2
N2 G97 S800 G95 F0.05 M3
N3 G0 X62 Z2
N4 #g1 = -10
N5 L"groove" LA50 LB8 Q3 [ three grooves 8 mm apart: Z-10, Z-18, Z-26 ]
N6 L"groove" LA44 LB0 [ a deeper one at Z-34 ]
N7 G0 X62 Z2
N8 G14 Q0
N9 M30
END
SUBPROGRAM "groove"
N100 G0 X62 Z#g1
N101 G1 X#__la
N102 G0 X62
N103 #g1 = #g1 - #__lb
RETURN
