0  BEGIN PGM HELIX_P1 MM
; LinuxCNC comparison: a helix of radius 10 mm, pitch 1 mm, 3 turns at F3000.
1  CC X+10 Y+0
2  CP IPA+1080 IZ+3 DR+ F3000
3  END PGM HELIX_P1 MM
