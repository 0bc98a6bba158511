//! `klar plot`: every example program gives a PNG of the right size and a well-formed SVG, and
//! the flattened toolpath stays within the chord tolerance of the programmed arcs.

use klar::plot::{CHORD_TOLERANCE, plot_program, toolpath};
use klar_interp::Pose;
use std::path::Path;

fn programs() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs");
    let mut out: Vec<_> = std::fs::read_dir(dir)
        .expect("programs/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("h")))
        .collect();
    out.sort();
    out
}

fn start() -> Pose {
    Pose::xyz(0.0, 0.0, 100.0)
}

#[test]
fn every_program_plots_to_png_and_svg() {
    let dir = std::env::temp_dir().join(format!("klar-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let progs = programs();
    assert!(progs.len() >= 2);
    for p in progs {
        let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
        let png = dir.join(format!("{stem}.png"));
        plot_program(&p, start(), &png).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{stem}: not a PNG");
        // IHDR: width and height, big-endian, at bytes 16..24.
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
        assert_eq!((w, h), (1400, 700));

        let svg = dir.join(format!("{stem}.svg"));
        plot_program(&p, start(), &svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(
            text.trim_start().starts_with("<svg"),
            "{stem}: no <svg> root"
        );
        assert!(
            text.trim_end().ends_with("</svg>"),
            "{stem}: unterminated svg"
        );
        assert!(
            text.contains("<polyline") || text.contains("<path"),
            "{stem}: nothing drawn"
        );
    }
}

#[test]
fn flattened_helix_stays_on_the_cylinder() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/helix_thread.h");
    let strokes = toolpath(&p, start()).unwrap();
    // Helix points: radius 15 about the origin between Z-8.25 and Z+0.75 (from the program).
    let mut n = 0;
    for s in &strokes {
        for w in s.points.windows(2) {
            let [a, b] = [w[0], w[1]];
            if a[2] > -8.25 && b[2] < 0.75 && a[0].hypot(a[1]) > 1.0 && b[0].hypot(b[1]) > 1.0 {
                n += 1;
                assert!((a[0].hypot(a[1]) - 15.0).abs() < 1e-9);
                // The chord midpoint is at most the chord tolerance inside the circle.
                let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                let sag = 15.0 - mid[0].hypot(mid[1]);
                assert!((0.0..=CHORD_TOLERANCE + 1e-12).contains(&sag), "sag {sag}");
            }
        }
    }
    assert!(n > 100, "{n} helix chords");
}

#[test]
fn a_bad_output_name_is_refused() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/rectangle.h");
    let err = plot_program(&p, start(), Path::new("out.jpg")).unwrap_err();
    assert!(err.to_string().contains(".svg or .png"), "{err}");
}
