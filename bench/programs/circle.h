0  BEGIN PGM CIRCLE MM
; A full circle of radius 10 mm, started on the circle (centre X+10 Y+0), F6000.
1  CC X+10 Y+0
2  C X+0 Y+0 DR+ F6000
3  END PGM CIRCLE MM
