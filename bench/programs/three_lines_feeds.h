0 BEGIN PGM THREE_LINES_FEEDS MM
; A slow block between two fast ones with a 0.1 mrad kink at its start (3-decimal CAM output).
1 L X+0 Y+0 Z+0 R0 FMAX
2 L X+50 F1206
3 L X+53 Y+0.0003 F302
4 L X+100 Y+0.0003 F1206
5 END PGM THREE_LINES_FEEDS MM
