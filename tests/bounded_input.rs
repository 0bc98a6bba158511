//! End-to-end: hostile and accidental input never exhausts the machine. A program that is one
//! huge line, a FIFO or a device given as a file, machine values outside their physical ranges
//! and programs that loop forever with motion all end in a clear message, and each `klar`
//! child stays within a small peak memory (measured by `wait4`) and a bounded time.
#![cfg(target_os = "linux")]

mod common;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Peak resident memory a `klar` child may reach on hostile input, kB. The debug binary starts
/// at about 10 MB; before the bounds, a 64 MB line took it past 1 GB.
const PEAK_KB: i64 = 32 * 1024;

/// Longest a child may take before it is killed and the test fails.
const DEADLINE: Duration = Duration::from_secs(60);

/// What a `klar` child did.
struct Measured {
    code: i32,
    stdout: String,
    stderr: String,
    /// Peak resident set, kB (`ru_maxrss` of this child alone).
    peak_kb: i64,
}

/// Data memory a child may map at all, bytes: a regression fails the test instead of taking
/// the machine's memory.
const DATA_LIMIT: u64 = 256 * 1024 * 1024;

/// Runs `klar args` and measures its peak memory; kills it (and fails) past [`DEADLINE`].
///
/// The child is forked (a `pre_exec` step; a spawned child sharing the test's memory until
/// its exec would report the test's own peak), so its `ru_maxrss` is the larger of the test's
/// resident set at the fork (a few MB: the tests hold no large buffers) and klar's own peak.
// the child is reaped by `wait4` (for its rusage), which clippy cannot see
#[allow(clippy::zombie_processes)]
fn klar(args: &[&str]) -> Measured {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_klar"));
    // SAFETY: setrlimit is async-signal-safe and touches no memory of the parent.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: DATA_LIMIT as libc::rlim_t,
                rlim_max: DATA_LIMIT as libc::rlim_t,
            };
            if libc::setrlimit(libc::RLIMIT_DATA, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let mut child = cmd
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("klar starts");
    let pid = i32::try_from(child.id()).expect("pid");
    let drain = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut v = Vec::new();
            let _ = r.read_to_end(&mut v);
            String::from_utf8_lossy(&v).into_owned()
        })
    };
    let out = drain(Box::new(child.stdout.take().expect("stdout")));
    let err = drain(Box::new(child.stderr.take().expect("stderr")));
    let start = Instant::now();
    let (status, usage) = loop {
        let mut status = 0;
        // SAFETY: an all-zero rusage is valid, and wait4 writes into the two locals only.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: pid is our own child, not yet waited for.
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break (status, usage);
        }
        assert_eq!(r, 0, "wait4 failed");
        if start.elapsed() > DEADLINE {
            let _ = child.kill();
            let _ = child.wait();
            panic!("klar {args:?} did not end within {DEADLINE:?}");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Measured {
        code: if libc::WIFEXITED(status) {
            libc::WEXITSTATUS(status)
        } else {
            -1
        },
        stdout: out.join().expect("stdout reader"),
        stderr: err.join().expect("stderr reader"),
        peak_kb: usage.ru_maxrss,
    }
}

/// A folder of its own for a test's files, removed on drop.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let d = std::env::temp_dir().join(format!("klar-bounded-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).expect("scratch folder");
        Scratch(d)
    }

    fn file(&self, name: &str, bytes: &[u8]) -> String {
        let p = self.0.join(name);
        std::fs::write(&p, bytes).expect("write");
        p.to_string_lossy().into_owned()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn small(m: &Measured, what: &str) {
    eprintln!("{what}: peak {} kB", m.peak_kb);
    assert!(
        m.peak_kb < PEAK_KB,
        "{what}: peak memory {} kB (bound {PEAK_KB} kB)",
        m.peak_kb
    );
}

#[test]
fn a_program_of_one_huge_line_is_refused_in_bounded_memory() {
    let s = Scratch::new("line");
    // 64 MB without a line end, after two good lines, written in pieces
    let p = s.file("huge.h", b"0 BEGIN PGM T MM\n1 L X+0 R0 FMAX\n");
    {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&p)
            .expect("open");
        let piece = vec![b'X'; 1024 * 1024];
        for _ in 0..64 {
            f.write_all(&piece).expect("write");
        }
    }
    let said = format!(
        "{p}:3:1: cannot read program: block longer than {} characters (klar's limit for one block",
        klar_interp::MAX_BLOCK_BYTES
    );
    for args in [
        vec!["check", &p],
        vec!["check", "--program-only", &p],
        vec!["run", &p],
        vec!["ops", &p],
    ] {
        let m = klar(&args);
        assert_eq!(m.code, 1, "{args:?}: {}", m.stderr);
        assert!(m.stderr.contains(&said), "{args:?}: {}", m.stderr);
        // the snippet quotes a window of the line, not the line
        let quoted = format!("{}…", "X".repeat(klar_interp::MAX_QUOTED_CHARS));
        assert!(m.stderr.contains(&quoted), "{args:?}: {}", m.stderr);
        assert!(
            m.stderr.len() < 8 * 1024,
            "{args:?}: {} bytes said",
            m.stderr.len()
        );
        small(&m, &format!("{args:?}"));
    }
}

#[test]
fn a_long_word_is_quoted_shortened() {
    let s = Scratch::new("word");
    let word = "Q".repeat(3000);
    let p = s.file(
        "word.h",
        format!("0 BEGIN PGM T MM\n1 L X+1 {word}\n2 END PGM T MM\n").as_bytes(),
    );
    let m = klar(&["check", "--program-only", &p]);
    assert_eq!(m.code, 1, "{}", m.stderr);
    let first = m.stderr.lines().next().unwrap_or("");
    let quoted = format!("'{}…", "Q".repeat(klar_interp::MAX_QUOTED_CHARS - 1));
    assert_eq!(
        first,
        format!("{p}:2:9: block 1: unknown word {quoted} in L block")
    );
}

#[test]
fn fifos_devices_and_folders_are_refused_as_files() {
    let s = Scratch::new("kinds");
    let fifo = s.0.join("pipe.h");
    let c = std::ffi::CString::new(fifo.to_string_lossy().as_bytes()).expect("path");
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
    let fifo = fifo.to_string_lossy().into_owned();
    let folder = s.0.to_string_lossy().into_owned();
    let good = s.file(
        "good.h",
        b"0 BEGIN PGM T MM\n1 L X+1 R0 FMAX\n2 END PGM T MM\n",
    );
    for (path, kind) in [
        (fifo.as_str(), "a FIFO"),
        ("/dev/zero", "a device"),
        (folder.as_str(), "a folder"),
    ] {
        for cmd in ["check", "run", "ops"] {
            let m = klar(&[cmd, path]);
            assert_eq!(m.code, 1, "{cmd} {path}: {}", m.stderr);
            assert!(
                m.stderr.contains(&format!(
                    "{path}:1:1: not a regular file ({kind}): a program is read from a file"
                )),
                "{cmd} {path}: {}",
                m.stderr
            );
            small(&m, path);
        }
        let m = klar(&["check", &good, "--machine", path]);
        assert_eq!(m.code, 1, "machine {path}: {}", m.stderr);
        assert!(
            m.stderr
                .contains(&format!("{path}: not a regular file ({kind})")),
            "machine {path}: {}",
            m.stderr
        );
    }
}

/// The built-in mill's TOML with `from` replaced by `to`, written as a machine file.
fn machine(s: &Scratch, name: &str, base: &str, from: &str, to: &str) -> String {
    let text = base.replacen(from, to, 1);
    assert_ne!(text, base, "{from} not in the machine");
    s.file(name, text.as_bytes())
}

#[test]
fn machine_values_outside_their_ranges_are_refused_by_key() {
    let s = Scratch::new("ranges");
    let prog = s.file(
        "p.h",
        b"0 BEGIN PGM T MM\n1 L X+10 Y+10 R0 F1000\n2 END PGM T MM\n",
    );
    let mill = klar::config::BUILTIN_MILL;
    let mill5 = klar::config::BUILTIN_MILL5;
    let cases = [
        (
            machine(
                &s,
                "a.toml",
                mill,
                "max_acceleration = 2000.0",
                "max_acceleration = 1e-300",
            ),
            "axis X: max_acceleration = 1e-300 is outside the range 0.1 … 10000000 mm/s²",
        ),
        (
            machine(
                &s,
                "v.toml",
                mill,
                "max_velocity = 166.0",
                "max_velocity = 1e-300",
            ),
            "axis X: max_velocity = 1e-300 is outside the range 0.01 … 100000 mm/s",
        ),
        (
            machine(
                &s,
                "s.toml",
                mill,
                "servo_period = 0.001",
                "servo_period = 1e-9",
            ),
            "servo_period = 1e-9 is outside the range 5e-5 … 0.1 s",
        ),
        (
            machine(
                &s,
                "p.toml",
                mill5,
                "tilt_pivot = [0.0, 0.0, -100.0]",
                "tilt_pivot = [0.0, 0.0, -1e12]",
            ),
            "table_table.tilt_pivot = -1e12 is outside the range -10000 … 10000 mm",
        ),
    ];
    for (file, said) in &cases {
        // The message starts at the key's line and column in the file.
        let text = std::fs::read_to_string(file).expect("machine file");
        let key = said
            .split(" = ")
            .next()
            .and_then(|k| k.rsplit(['.', ' ']).next())
            .expect("key");
        let (row, col) = text
            .lines()
            .enumerate()
            .find_map(|(i, l)| {
                let c = l.find(&format!("{key} = "))?;
                (l.contains("1e-") || l.contains("1e12")).then_some(())?;
                Some((i + 1, c + 1))
            })
            .expect("changed line");
        for cmd in ["check", "run"] {
            let m = klar(&[cmd, &prog, "--machine", file]);
            assert_eq!(m.code, 1, "{cmd} {file}: {}", m.stderr);
            assert!(
                m.stderr
                    .contains(&format!("{file}:{row}:{col}: {said} klar plans with")),
                "{cmd} {file}: {}",
                m.stderr
            );
            small(&m, file);
        }
    }
}

/// A program that moves in a loop forever (an FN 9 jump back over two moves, line 9).
const ENDLESS: &str = "0 BEGIN PGM LOOP MM\n1 BLK FORM 0.1 Z X+0 Y+0 Z-20\n\
    2 BLK FORM 0.2 X+100 Y+100 Z+0\n3 TOOL CALL 1 Z S1000\n4 L Z+50 R0 FMAX\n5 LBL 1\n\
    6 L X+10 Y+10 R0 F1000\n7 L X+0 Y+0 R0 F1000\n8 FN 9: IF +0 EQU +0 GOTO LBL 1\n\
    9 END PGM LOOP MM\n";

#[test]
fn an_endless_loop_with_motion_is_undecided_at_a_stated_limit() {
    let s = Scratch::new("loop");
    let p = s.file("loop.h", ENDLESS.as_bytes());
    let jump = "the jump at line 9 ran more than 100000 times";
    // executed blocks
    let m = klar(&["check", &p, "--max-blocks", "1000"]);
    assert_eq!(m.code, 2, "{}", m.stderr);
    let line = m
        .stderr
        .lines()
        .find(|l| l.contains("undecided"))
        .unwrap_or_else(|| panic!("no undecided line: {}", m.stderr));
    assert!(
        line.starts_with(&format!(
            "{p}:7:1: block 6: undecided: the program did not end within 1000 executed blocks"
        )),
        "{line}"
    );
    assert!(line.contains(jump), "{line}");
    assert!(!m.stdout.contains("ok"), "{}", m.stdout);
    small(&m, "check --max-blocks");
    // machine time: each pass of the loop takes about 1.7 s, so 60 s end in a move
    let m = klar(&["check", &p, "--max-machine-time", "60"]);
    assert_eq!(m.code, 2, "{}", m.stderr);
    assert!(
        m.stderr
            .contains("undecided: the program did not end within 60 s of machine time"),
        "{}",
        m.stderr
    );
    assert!(m.stderr.contains(jump), "{}", m.stderr);
    small(&m, "check --max-machine-time");
    // klar ops stops after the stated number of ops
    let m = klar(&["ops", &p, "--max-ops", "500"]);
    assert_eq!(m.code, 2, "{}", m.stderr);
    assert_eq!(m.stdout.lines().count(), 500);
    assert!(
        m.stderr
            .contains("undecided: the program did not end within 500 ops"),
        "{}",
        m.stderr
    );
    small(&m, "ops --max-ops");
}

#[test]
fn a_loop_that_ends_passes_the_test_run() {
    // 110 000 jumps (more than the interpreter's check follows) that end: no error, no give-up
    let s = Scratch::new("ends");
    let p = s.file(
        "ends.h",
        b"0 BEGIN PGM E MM\n1 TOOL CALL 1 Z S1000\n2 Q1 = 0\n3 LBL 1\n4 L X+0.001 R0 F1000\n\
          5 L X+0 R0 F1000\n6 Q1 = Q1 + 1\n7 FN 12: IF +Q1 LT +110000 GOTO LBL 1\n8 END PGM E MM\n",
    );
    let m = klar(&["check", &p]);
    assert_eq!(m.code, 0, "{}", m.stderr);
    assert!(m.stdout.contains("ok on"), "{}", m.stdout);
    assert!(!m.stderr.contains("undecided"), "{}", m.stderr);
}

#[test]
fn check_limits_have_their_stated_defaults() {
    assert_eq!(klar::testrun::MAX_PLANNED_TIME, 24.0 * 3600.0);
    assert_eq!(klar::testrun::MAX_SERVO_CYCLES, 100_000_000);
    assert_eq!(klar::testrun::MAX_EXECUTED_BLOCKS, 10_000_000);
    assert!(Path::new(env!("CARGO_BIN_EXE_klar")).exists());
}
