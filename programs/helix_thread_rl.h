0  BEGIN PGM HELIX_THREAD_RL MM
; The internal right-hand thread of helix_thread.h programmed on the thread contour with radius
; compensation, as the TNC manual's table says for internal, right-hand, work direction Z+:
; DR+ with RL. Thread M40 x 1.5: contour radius 20, thread mill R5 (DR+5 while no tool table
; is configured), so the tool centre runs at radius 15.
;   IPA = 6 * 360 = 2160, IZ = 1.5 * 6 = 9, start Z = -1.5 * (5 + 0.5) = -8.25
1  BLK FORM 0.1 Z X-40 Y-40 Z-20
2  BLK FORM 0.2 X+40 Y+40 Z+0
3  TOOL CALL 1 Z S2000 DR+5
4  L Z+20 R0 FMAX M3
5  CC X+0 Y+0
6  L X+0 Y+0 FMAX
7  L Z-8.25 FMAX
8  LP PR+20 PA+0 RL F300
9  CP IPA+2160 IZ+9 DR+ F200
10 L X+0 Y+0 R0 F300
11 L Z+20 FMAX M30
12 END PGM HELIX_THREAD_RL MM
