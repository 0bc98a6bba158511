//! `klar plot`: every example program gives a PNG of the right size and a well-formed SVG;
//! the flattened toolpath stays within the chord tolerance of the programmed arcs; the
//! tool-centre path lies one tool radius off the contour; the motion profile of a single line
//! shows the programmed feed, the machine's limits and the programmed distance.

use klar::config::MachineConfig;
use klar::plot::profile::profile;
use klar::plot::{CHORD_TOLERANCE, plot_program, plot_program_with, tool_centre_path, toolpath};
use klar_interp::{AxisLetter, Pose};
use std::path::{Path, PathBuf};

/// Every program in programs/ and one folder down (.h, .i, .nc), without programs/bad/
/// (the deliberately broken ones).
fn programs() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs");
    let mut dirs = vec![root.clone()];
    let mut out = Vec::new();
    for e in std::fs::read_dir(&root)
        .expect("programs/ exists")
        .flatten()
    {
        if e.path().is_dir() && e.file_name() != "bad" {
            dirs.push(e.path());
        }
    }
    for d in dirs {
        for e in std::fs::read_dir(d).expect("readable").flatten() {
            let p = e.path();
            let ext = p
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase());
            if matches!(ext.as_deref(), Some("h" | "i" | "nc")) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    // IHDR: width and height, big-endian, at bytes 16..24.
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    (w, h)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("klar-plot-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn start() -> Pose {
    Pose::xyz(0.0, 0.0, 100.0)
}

#[test]
fn every_program_plots_to_png_and_svg() {
    let dir = scratch("all");
    let progs = programs();
    assert!(progs.len() >= 4);
    for p in progs {
        let stem = p.file_name().unwrap().to_string_lossy().replace('.', "_");
        let png = dir.join(format!("{stem}.png"));
        // probing programs need a machine with the simulated probe and part: the one they
        // name in their comments (`machines/probing….toml`), else the probing mill
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        let named = text.find("machines/probing").and_then(|i| {
            let rest = &text[i..];
            rest.find(".toml").map(|j| rest[..j + 5].to_string())
        });
        let probes = text.contains("TCH PROBE") || named.is_some();
        let file = named.unwrap_or_else(|| "machines/probing-mill.toml".to_string());
        let machine = probes.then(|| {
            klar::config::MachineConfig::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(&file))
                .expect("probing machine")
        });
        plot_program_with(&p, machine.as_ref(), start(), &png, None)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(png_size(&bytes), (1400, 700), "{stem}");

        let svg = dir.join(format!("{stem}.svg"));
        plot_program_with(&p, machine.as_ref(), start(), &svg, None).unwrap();
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
    let strokes = toolpath(&p, None, start()).unwrap();
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

#[test]
fn the_tool_centre_runs_one_radius_outside_the_rl_rectangle() {
    // rectangle_rl.h: the 100 x 60 rectangle with RL and a tool of radius 5 (DR+5), run
    // clockwise, so the centre runs outside: top edge at Y+65, right edge at X+105, bottom
    // edge at Y-5, left edge at X-5.
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/rectangle_rl.h");
    let contour = toolpath(&p, None, start()).unwrap();
    let centre = tool_centre_path(&p, None, start()).unwrap();
    assert_ne!(contour, centre);
    let pts: Vec<[f64; 3]> = centre
        .iter()
        .filter(|s| !s.rapid)
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| (p[2] + 5.0).abs() < 1e-9)
        .collect();
    let near = |v: f64, want: f64| (v - want).abs() < 1e-9;
    let top: Vec<_> = pts.iter().filter(|p| p[1] > 62.0).collect();
    let right: Vec<_> = pts.iter().filter(|p| p[0] > 102.0).collect();
    let bottom: Vec<_> = pts.iter().filter(|p| p[1] < -2.0).collect();
    assert!(top.len() >= 2 && right.len() >= 2 && bottom.len() >= 2);
    assert!(top.iter().all(|p| p[1] <= 65.0 + 1e-9));
    // The top edge is one straight piece along Y+65 from above X+10 to above X+80.
    let edge = centre.iter().filter(|s| !s.rapid).any(|s| {
        s.points.windows(2).any(|w| {
            near(w[0][1], 65.0) && near(w[1][1], 65.0) && near(w[0][0], 10.0) && near(w[1][0], 80.0)
        })
    });
    assert!(edge, "no straight top edge at Y+65 from X+10 to X+80");
    assert!(right.iter().all(|p| p[0] <= 105.0 + 1e-9));
    assert!(right.iter().any(|p| near(p[0], 105.0)));
    assert!(bottom.iter().all(|p| p[1] >= -5.0 - 1e-9));
    assert!(bottom.iter().any(|p| near(p[1], -5.0)));
    // Every centre point at cutting depth is one radius from the contour (within the chord
    // tolerance of both flattenings); the lead-in and lead-out along Y+10 left of X-5 are
    // farther away.
    let segments: Vec<[[f64; 3]; 2]> = contour
        .iter()
        .filter(|s| !s.rapid)
        .flat_map(|s| s.points.windows(2).map(|w| [w[0], w[1]]))
        .filter(|w| (w[0][2] + 5.0).abs() < 1e-9 && (w[1][2] + 5.0).abs() < 1e-9)
        .filter(|w| w[0][0] >= -1e-9 && w[1][0] >= -1e-9)
        .collect();
    assert!(segments.len() > 20);
    let tol = 2.0 * CHORD_TOLERANCE + 1e-9;
    for p in &pts {
        let d = segments
            .iter()
            .map(|[a, b]| distance_to_segment([p[0], p[1]], [a[0], a[1]], [b[0], b[1]]))
            .fold(f64::INFINITY, f64::min);
        assert!(d >= 5.0 - tol, "centre point {p:?} is {d} from the contour");
        if p[0] > -5.0 + 1e-6 {
            assert!(d <= 5.0 + tol, "centre point {p:?} is {d} from the contour");
        }
    }
}

fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// A program of one feed move: X+50 at F6000 (100 mm/s) from the mill's start X0 Y0 Z100.
const ONE_LINE: &str = "0 BEGIN PGM ONE MM\n1 L X+50 R0 F6000\n2 END PGM ONE MM\n";

#[test]
fn the_profile_of_one_line_shows_its_feed_limits_and_length() {
    let dir = scratch("profile");
    let prog = dir.join("one.h");
    std::fs::write(&prog, ONE_LINE).unwrap();
    let mill = MachineConfig::builtin_mill();
    let p = profile(&prog, &mill).unwrap();
    let x = p.axis(AxisLetter::X).unwrap();
    let (y, z) = (
        p.axis(AxisLetter::Y).unwrap(),
        p.axis(AxisLetter::Z).unwrap(),
    );
    assert!(p.t.len() > 100 && p.t.len() == x.velocity.len());
    // The programmed feed is reached and never exceeded: 6000 mm/min = 100 mm/s.
    let top = p.path_speed.iter().cloned().fold(0.0, f64::max);
    assert!((top - 100.0).abs() < 1e-6, "top speed {top}");
    // The mill's X limits (machines/mill.toml): 2000 mm/s², 50000 mm/s³.
    let amax = x.acceleration.iter().map(|a| a.abs()).fold(0.0, f64::max);
    let jmax = x.jerk.iter().map(|j| j.abs()).fold(0.0, f64::max);
    assert!(amax <= 2000.0 * (1.0 + 1e-6), "acceleration {amax}");
    assert!(
        amax > 1000.0,
        "acceleration {amax}: the move should use the axis"
    );
    assert!(jmax <= 50000.0 * (1.0 + 1e-6), "jerk {jmax}");
    // Y and Z stand still; X covers the programmed 50 mm (sum of v·dt over every cycle).
    assert!(y.velocity.iter().chain(&z.velocity).all(|v| *v == 0.0));
    let mut dist = 0.0;
    let mut last_t = 0.0;
    for (t, v) in p.t.iter().zip(&x.velocity) {
        dist += v * (t - last_t);
        last_t = *t;
    }
    assert!((dist - 50.0).abs() < 1e-6, "distance {dist}");
    // At 100 mm/s the move needs at least 0.5 s.
    assert!(p.machine_time > 0.5);

    let png = dir.join("one.png");
    plot_program_with(&prog, None, start(), &png, Some(&p)).unwrap();
    assert_eq!(png_size(&std::fs::read(&png).unwrap()), (1400, 1500));
    let svg = dir.join("one.svg");
    plot_program_with(&prog, None, start(), &svg, Some(&p)).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("path speed") && text.contains("jerk"));
}

#[test]
fn a_profile_of_a_broken_program_names_the_line() {
    let dir = scratch("broken");
    let prog = dir.join("bad.h");
    std::fs::write(
        &prog,
        "0 BEGIN PGM BAD MM\n1 L X+50 Q R0 F6000 %%\n2 END PGM BAD MM\n",
    )
    .unwrap();
    let err = profile(&prog, &MachineConfig::builtin_mill()).unwrap_err();
    assert!(err.to_string().contains("bad.h:2:"), "{err}");
}

#[test]
fn broken_programs_give_errors_not_pictures() {
    let bad = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/bad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&bad)
        .expect("programs/bad exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.file_name().is_some_and(|n| n != "EXPECTED"))
        .collect();
    files.sort();
    assert!(files.len() >= 5);
    let dir = scratch("bad");
    for p in files {
        let out = dir.join("bad.png");
        let _ = std::fs::remove_file(&out);
        let err = plot_program(&p, start(), &out).expect_err(&p.display().to_string());
        assert!(!err.to_string().is_empty());
        assert!(
            !out.exists(),
            "{}: a picture of a broken program",
            p.display()
        );
    }
}

#[test]
fn a_lathe_plot_reads_x_as_a_diameter_and_frames_the_cuts() {
    let dir = scratch("lathe");
    let prog = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs/lathe/groove_g860.nc");
    let svg = dir.join("g860.svg");
    plot_program(&prog, start(), &svg).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("X ⌀ [mm]"), "no diameter label");
    // the cuts span Ø40..Ø54 and Z-31..-20: framed on them, the ticks lie near that
    // range (Ø40 appears as a tick); framed on the tool change point Ø200/Z200 too, the
    // working plane's ticks would run in steps of tens up to about 200
    let ticks: Vec<f64> = text
        .split('>')
        .filter_map(|t| t.split('<').next())
        .filter_map(|t| t.trim().parse::<f64>().ok())
        .collect();
    assert!(ticks.contains(&40.0) && ticks.contains(&52.0), "{ticks:?}");
    assert!(!ticks.contains(&400.0), "{ticks:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
