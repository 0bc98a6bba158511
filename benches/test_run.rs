//! The test run (`klar check --machine`) on CAM-style programs: machine time checked per
//! second of CPU time. The counter is the servo periods of planned machine time (1 ms each on
//! the bench machine), so divan's items per second divided by 1000 is the ratio of machine
//! time to check time.
//!
//! Two programs written by the bench itself into a temporary folder, on the bench machine
//! (`bench/machine-jerk-1e5.toml`: X Y Z 100 mm/s, 1000 mm/s², 1e5 mm/s³, 0.01 mm):
//! * parallel finishing: passes along X in 0.25 mm chords over a curved surface at F2400,
//!   each turned into the next by a stepover at F400 (up, a half circle in YZ, down);
//! * adaptive-style clearing: loops of 0.3 mm chords advancing 0.5 mm each, the cutting half
//!   at F1800 and the return half at F3000 (the slow case: the path brakes for the feed
//!   change twice a loop).

use klar::config::MachineConfig;
use klar::testrun::test_run;
use std::fmt::Write;
use std::path::{Path, PathBuf};

fn main() {
    divan::main();
}

/// Klartext lines, numbered when written.
struct Program {
    lines: Vec<String>,
    feed: Option<u32>,
}

impl Program {
    fn new() -> Program {
        Program {
            lines: vec!["L Z+5.000 FMAX".to_string()],
            feed: None,
        }
    }

    /// `L` to the given axis words at `feed` (mm/min; the word only where it changes).
    fn line(&mut self, words: &[(char, f64)], feed: u32) {
        let mut text = "L".to_string();
        for (axis, value) in words {
            let _ = write!(text, " {axis}{value:+.3}");
        }
        if self.feed != Some(feed) {
            let _ = write!(text, " F{feed}");
            self.feed = Some(feed);
        }
        self.lines.push(text);
    }

    fn text(&self, name: &str) -> String {
        let mut out = format!("0 BEGIN PGM {name} MM\n");
        for (n, line) in self.lines.iter().enumerate() {
            let _ = writeln!(out, "{} {line}", n + 1);
        }
        let _ = writeln!(out, "{} END PGM {name} MM", self.lines.len() + 1);
        out
    }
}

/// Parallel finishing of z = 3·cos(x/10)·cos(y/15) − 8 over 60 × 40 mm in `passes` passes.
fn parallel(passes: usize) -> String {
    let z = |x: f64, y: f64| 3.0 * (x / 10.0).cos() * (y / 15.0).cos() - 8.0;
    let mut p = Program::new();
    p.lines.push("L X-30.000 Y-20.000 FMAX".into());
    p.line(&[('Z', z(-30.0, -20.0))], 400);
    let step = 40.0 / passes as f64;
    for pass in 0..passes {
        let y = -20.0 + pass as f64 * step;
        let mut xs: Vec<f64> = (0..=240).map(|i| -30.0 + 0.25 * i as f64).collect();
        if pass % 2 == 1 {
            xs.reverse();
        }
        for &x in &xs {
            p.line(&[('X', x), ('Y', y), ('Z', z(x, y))], 2400);
        }
        if pass + 1 == passes {
            break;
        }
        let x = xs[xs.len() - 1];
        let top = z(x, y).max(z(x, y + step)) + 0.5 * step;
        p.line(&[('Z', top)], 400);
        p.lines
            .push(format!("CC Y{:+.3} Z{top:+.3}", y + 0.5 * step));
        p.lines.push(format!("C Y{:+.3} Z{top:+.3} DR-", y + step));
        p.line(&[('Z', z(x, y + step))], 400);
    }
    p.lines.push("L Z+5.000 FMAX".into());
    p.text("BENCH_PARALLEL")
}

/// Adaptive-style clearing: `loops` loops of radius 4 mm along X.
fn pocket(loops: usize) -> String {
    let mut p = Program::new();
    p.lines.push("L X+4.000 Y+0.000 FMAX".into());
    p.line(&[('Z', -5.0)], 600);
    let r = 4.0;
    let n = (2.0 * std::f64::consts::PI * r / 0.3) as usize;
    for k in 0..loops {
        let cx = k as f64 * 0.5;
        for i in 1..=n {
            let phi = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            let feed = if phi < std::f64::consts::PI {
                1800
            } else {
                3000
            };
            let x = cx + r * phi.cos() + 0.5 * i as f64 / n as f64;
            p.line(&[('X', x), ('Y', r * phi.sin())], feed);
        }
    }
    p.lines.push("L Z+5.000 FMAX".into());
    p.text("BENCH_POCKET")
}

/// The bench machine of the repository's `bench/` folder.
fn machine() -> MachineConfig {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/machine-jerk-1e5.toml");
    MachineConfig::load(&path).expect("the bench machine loads")
}

/// Writes `text` to a file of its own in the temporary folder.
fn write_program(name: &str, text: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("klar-bench-{}-{name}.h", std::process::id()));
    std::fs::write(&path, text).expect("the temporary folder is writable");
    path
}

/// Checks the program and counts its planned machine time in servo periods.
fn check(bencher: divan::Bencher, name: &str, text: &str) {
    let config = machine();
    let path = write_program(name, text);
    let report = test_run(&path, &config);
    assert!(report.passed(), "{:?}", report.errors);
    let periods = (report.planned_time / 0.001).round() as u64;
    bencher
        .counter(divan::counter::ItemsCount::new(periods))
        .bench(|| divan::black_box(test_run(&path, &config).planned_time));
    let _ = std::fs::remove_file(&path);
}

/// Parallel finishing, 10 passes (about 2,450 lines, 33 s of machine time).
#[divan::bench(sample_count = 10, sample_size = 1)]
fn parallel_finishing(bencher: divan::Bencher) {
    check(bencher, "parallel", &parallel(10));
}

/// Adaptive-style clearing, 30 loops (about 2,500 lines, 33 s of machine time).
#[divan::bench(sample_count = 10, sample_size = 1)]
fn adaptive_clearing(bencher: divan::Bencher) {
    check(bencher, "pocket", &pocket(30));
}
