%variables_loops.nc
[ DIN PLUS variables and control structures: roughing passes counted by a WHILE loop, ]
[ a chamfer chosen by IF, and three grooves whose depths a SWITCH picks in a REPEAT    ]
[ loop. X is programmed as a diameter.                                                 ]
HEADER
#MATERIAL  C45
MACHINING
N1 T1
N2 G96 S180 G95 F0.25 M4
N3 #g1 = 60 [ blank diameter ]
N4 #g2 = 40 [ finished diameter ]
N5 #l1 = #g1 - 4 [ first pass: 2 mm depth of cut ]
N6 G0 X#g1 Z2
N7 WHILE (#l1 >= #g2)
N8 G0 X#l1
N9 G1 Z-30
N10 G0 Xi2 Z2
N11 #l1 = #l1 - 4
N12 ENDWHILE
N13 IF (#l1 + 4 == #g2) THEN [ the last pass reached the finished diameter ]
N14 G0 X(#g2 - 2) Z1
N15 G1 X#g2 Z0
N16 ELSE
N17 G0 X#g2 Z2
N18 ENDIF
N19 G0 X(#g1 + 2) Z2
N20 T2
N21 G97 S800 G95 F0.05 M3
N22 #l2 = 0
N23 REPEAT
N24 #l2 = #l2 + 1
N25 SWITCH #l2
N26 CASE 1
N27 #l3 = 36
N28 BREAK
N29 CASE 2
N30 #l3 = 34
N31 BREAK
N32 DEFAULT
N33 #l3 = 38
N34 ENDSWITCH
N35 G0 X(#g2 + 2) Z(-8 * #l2)
N36 G1 X#l3
N37 G0 X(#g2 + 2)
N38 UNTIL (#l2 >= 3)
N39 G14 Q0
N40 M30
END
