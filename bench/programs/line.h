0  BEGIN PGM LINE MM
; A 100 mm line at the axis speed limit (100 mm/s = F6000).
1  L X+100 F6000
2  END PGM LINE MM
