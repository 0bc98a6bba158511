0  BEGIN PGM HELIX_P2 MM
; A helix of radius 10 mm, pitch 2 mm, 3 turns (centre X+10 Y+0), F6000.
1  CC X+10 Y+0
2  CP IPA+1080 IZ+6 DR+ F6000
3  END PGM HELIX_P2 MM
