0  BEGIN PGM AUX_AXES MM
; For machines/modbus-sim.toml: a rotary table C positioned by a Modbus drive, a quill W on
; a stepper, and the spindle on a Modbus VFD. The auxiliary axes move in blocks of their own.
1  TOOL CALL 1 Z S6000
2  L Z+50 R0 FMAX M3
3  L C+90 FMAX
4  L W+10 F600
5  L X+20 Y+10 F2000
6  L X+40
7  L C+0 FMAX
8  L W+0 F600
9  L Z+100 FMAX M5
10 END PGM AUX_AXES MM
