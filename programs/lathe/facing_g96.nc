%facing_g96.nc
[ Constant surface speed: a face cut to the centre at 200 m/min under the G26 speed limit ]
[ of 2500 rpm. The spindle speed follows the tool's diameter every servo cycle, ]
[ n = Vc*1000/(pi*D), rises towards the centre and stays at the limit from D = 25.5 mm ]
[ on; G97 then turns the spindle at a constant 800 rpm again. ]
HEADER
#MATERIAL  C45
#UNIT      METRIC
TURRET
T1 ID"FACE-80"
MACHINING
N10 T1
N11 G26 S2500
N12 G0 X64 Z2
N13 G96 S200 G95 M3
N14 G0 X60 Z0
N15 G1 X0 F0.15
N16 G0 Z2
N17 G97 S800
N18 G0 X60
N19 G1 Z-5 F0.1
N20 G0 X64
N21 M30
END
