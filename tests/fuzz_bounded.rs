//! The bounded stable fuzz run: the cargo-fuzz target bodies (fuzz/common.rs) on inputs
//! mutated from the repository's own programs, machine files and protocol traffic, a fixed
//! number of executions per target, deterministic (seeded), so it fits in `cargo test` and
//! CI. A long run sets `KLAR_FUZZ_EXECS`; the open-ended coverage-guided run is
//! `scripts/fuzz.sh` (cargo-fuzz on stable with RUSTC_BOOTSTRAP=1, docs/safety.md). `KLAR_FUZZ_LAST=DIR` keeps
//! each target's input under test in DIR, so a hang or crash leaves its input behind.

#[path = "../fuzz/common.rs"]
mod targets;

use std::path::Path;

/// Executions per target in the bounded run; `KLAR_FUZZ_EXECS` raises it for a long run.
const EXECS: usize = 4000;

/// Executions of the whole-pipeline target, which plans up to 5 s of motion per input.
const PIPELINE_EXECS: usize = 150;

fn execs(default: usize) -> usize {
    std::env::var("KLAR_FUZZ_EXECS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// xorshift64*: deterministic mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

/// One mutation of `input`: a byte flip, an insertion of a dictionary word or random bytes,
/// a deletion, a duplication of a slice, or a splice with another seed.
fn mutate(rng: &mut Rng, input: &[u8], seeds: &[Vec<u8>], dictionary: &[&[u8]]) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..=rng.below(4) {
        let at = rng.below(v.len() + 1);
        match rng.below(6) {
            0 if !v.is_empty() => {
                let i = rng.below(v.len());
                v[i] ^= 1 << rng.below(8);
            }
            1 => {
                let word = dictionary[rng.below(dictionary.len())];
                v.splice(at..at, word.iter().copied());
            }
            2 => {
                let bytes: Vec<u8> = (0..rng.below(8) + 1).map(|_| rng.next() as u8).collect();
                v.splice(at..at, bytes);
            }
            3 if !v.is_empty() => {
                let end = (at + rng.below(16) + 1).min(v.len());
                let start = at.min(end);
                v.drain(start..end);
            }
            4 if !v.is_empty() => {
                let start = rng.below(v.len());
                let end = (start + rng.below(64) + 1).min(v.len());
                let piece = v[start..end].to_vec();
                v.splice(at..at, piece);
            }
            _ => {
                let other = &seeds[rng.below(seeds.len())];
                let cut = rng.below(other.len() + 1);
                v.truncate(at);
                v.extend_from_slice(&other[cut..]);
            }
        }
    }
    v
}

/// Runs `target` on every seed and then on `EXECS` mutants; returns the executions.
fn fuzz(
    name: &str,
    seed: u64,
    seeds: Vec<Vec<u8>>,
    dictionary: &[&[u8]],
    target: fn(&[u8]),
) -> usize {
    fuzz_n(name, seed, seeds, dictionary, target, EXECS)
}

/// Runs `target` on every seed and then on `default` mutants (or `KLAR_FUZZ_EXECS`).
fn fuzz_n(
    name: &str,
    seed: u64,
    seeds: Vec<Vec<u8>>,
    dictionary: &[&[u8]],
    target: fn(&[u8]),
    default: usize,
) -> usize {
    assert!(!seeds.is_empty(), "{name}: no seeds");
    let mut rng = Rng(seed);
    let mut count = 0;
    for s in &seeds {
        target(s);
        count += 1;
    }
    let last = std::env::var_os("KLAR_FUZZ_LAST").map(|d| Path::new(&d).join(name));
    let mut current = seeds[0].clone();
    for _ in 0..execs(default) {
        let base = if rng.below(4) == 0 {
            seeds[rng.below(seeds.len())].clone()
        } else {
            current
        };
        let input = mutate(&mut rng, &base, &seeds, dictionary);
        if let Some(path) = &last {
            // Keeps the input under test on disk: after a hang or a crash it is the finding.
            let _ = std::fs::write(path, &input);
        }
        target(&input);
        count += 1;
        // Keep inputs from growing without bound.
        current = if input.len() > 8192 { base } else { input };
    }
    eprintln!("fuzz {name}: {count} execs, no finding");
    count
}

fn files(dir: &str, ext: &str) -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut out: Vec<Vec<u8>> = std::fs::read_dir(&root)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .filter(|e| e.path().extension().is_some_and(|x| x == ext))
                .filter_map(|e| std::fs::read(e.path()).ok())
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

const PROGRAM_WORDS: &[&[u8]] = &[
    b"\n",
    b" ",
    b"L ",
    b"X+",
    b"Y-",
    b"Z+",
    b"CC ",
    b"C ",
    b"CR ",
    b"CT ",
    b"RND R",
    b"CHF ",
    b"R0 ",
    b"RL ",
    b"FMAX",
    b"F",
    b"M3",
    b"Q1 = ",
    b"FN 0: ",
    b"FN 14: ERROR = ",
    b"/ 0",
    b"LBL 1\n",
    b"CALL LBL 1 REP5\n",
    b"LBL 0\n",
    b"CYCL DEF ",
    b"TOOL CALL 1 Z S",
    b"APPR ",
    b"DEP ",
    b"IPA+",
    b"PR+",
    b"PA+",
    b"DR+",
    b"DR-",
    b"END PGM A MM\n",
    b"BEGIN PGM A MM\n",
    b"G01 ",
    b"G00 ",
    b"G02 ",
    b"I",
    b"J",
    b"N10 ",
    b"%A G71 *\n",
    b"T1 ",
    b"9999999999",
    b"1e308",
    b"-0",
    b"(",
    b")",
    b"[",
    b"]",
    b";",
    b"*",
];

#[test]
fn klartext_programs() {
    let mut seeds = files("programs", "h");
    seeds.extend(files("programs/bad", "h"));
    fuzz(
        "klartext",
        1,
        seeds,
        PROGRAM_WORDS,
        targets::program_klartext,
    );
}

#[test]
fn tnc_iso_programs() {
    let seeds = files("programs/iso", "i");
    fuzz("tnc_iso", 2, seeds, PROGRAM_WORDS, targets::program_tnc_iso);
}

#[test]
fn lathe_din_programs() {
    let seeds = files("programs/lathe", "nc");
    fuzz(
        "lathe_din",
        3,
        seeds,
        PROGRAM_WORDS,
        targets::program_lathe_din,
    );
}

#[test]
fn machine_files() {
    let seeds = files("machines", "toml");
    let words: &[&[u8]] = &[
        b"\n",
        b"=",
        b"[[axis]]\n",
        b"letter = \"A\"\n",
        b"kind = \"rotary\"\n",
        b"nan",
        b"inf",
        b"-1.0",
        b"0",
        b"1e400",
        b"\"",
        b"[",
        b"]",
        b"{",
        b"}",
        b"start_homed = true\n",
        b"[[fault]]\nat = 0.1\nkind = \"estop\"\n",
        b"following_error_limit = ",
        b"backend = { kind = \"sim\" }\n",
        b"[spindle]\nmax_rpm = ",
    ];
    fuzz("machine_toml", 4, seeds, words, targets::machine_toml);
}

#[test]
fn slcan_streams() {
    let seeds: Vec<Vec<u8>> = vec![
        b"t1238112233445566778899\r".to_vec(),
        b"T1234567F8AABBCCDDEEFF0011\rt70110\rr1230\rR123456780\r\x07\r".to_vec(),
        b"S6\rO\rC\rV1013\rN1234\rF00\rZ1\r".to_vec(),
    ];
    let words: &[&[u8]] = &[
        b"\r", b"t", b"T", b"r", b"R", b"F", b"8", b"0", b"\x07", b"G",
    ];
    fuzz("slcan", 5, seeds, words, targets::slcan_stream);
}

#[test]
fn canopen_frames() {
    // [id hi, id lo, len, data...]: boot-up, heartbeat, EMCY, TPDO1, SDO answer of node 1.
    let seeds: Vec<Vec<u8>> = vec![
        vec![0x07, 0x01, 1, 0x00, 0x07, 0x01, 1, 0x05],
        vec![0x00, 0x81, 8, 0x10, 0x23, 0x80, 1, 2, 3, 4, 5],
        vec![0x01, 0x81, 8, 0x37, 0x06, 0, 0, 0x10, 0x27, 0, 0],
        vec![0x05, 0x81, 8, 0x43, 0x41, 0x60, 0x00, 0x37, 0x06, 0, 0],
    ];
    let words: &[&[u8]] = &[
        &[0x07, 0x01, 1],
        &[0x05, 0x81, 8],
        &[0x00, 0x81, 8],
        &[0x80, 0, 0],
    ];
    fuzz("canopen", 6, seeds, words, targets::canopen_frames);
}

#[test]
fn whole_pipeline() {
    // Klartext as it is; TNC ISO and lathe DIN behind the byte that picks their dialect.
    let mut seeds = files("programs", "h");
    let prefixed = |byte: u8, dir: &str, ext: &str| {
        files(dir, ext).into_iter().map(move |p| {
            let mut v = vec![byte];
            v.extend(p);
            v
        })
    };
    seeds.extend(prefixed(1, "programs/iso", "i"));
    seeds.extend(prefixed(2, "programs/lathe", "nc"));
    fuzz_n(
        "pipeline",
        7,
        seeds,
        PROGRAM_WORDS,
        targets::pipeline,
        PIPELINE_EXECS,
    );
}

#[test]
fn the_pipeline_target_plans_each_dialect_within_the_limits() {
    let read = |p: &str| std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(p)).unwrap();
    let with = |byte: u8, p: &str| [vec![byte], read(p)].concat();
    for (name, input) in [
        ("klartext", read("programs/rectangle_rl.h")),
        (
            "klartext, first byte 0",
            with(0, "programs/plane_spatial.h"),
        ),
        ("tnc iso", with(1, "programs/iso/rectangle.i")),
        ("lathe din", with(2, "programs/lathe/shaft_turning.nc")),
    ] {
        let run = targets::pipeline_run(&input);
        // Real motion went through the planner and the kinematics, within every limit.
        assert!(run.ops > 5, "{name}: {run:?}");
        assert!(run.samples > 500, "{name}: {run:?}");
        assert_eq!(run.step_error, None, "{name}");
    }
    // Not a program: nothing reaches the planner.
    let run = targets::pipeline_run(b"\x01\xff\xfe garbage");
    assert_eq!((run.ops, run.samples), (0, 0));
}

/// A fuzz target body.
type Target = fn(&[u8]);

/// Every minimized finding in fuzz/findings/ goes through the target its file name starts
/// with (the README there says what each one did), so a fixed finding stays fixed.
#[test]
fn findings_replay() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/findings");
    let targets: [(&str, Target); 7] = [
        ("klartext_", targets::program_klartext),
        ("tnc_iso_", targets::program_tnc_iso),
        ("lathe_din_", targets::program_lathe_din),
        ("machine_toml_", targets::machine_toml),
        ("slcan_", targets::slcan_stream),
        ("canopen_", targets::canopen_frames),
        ("pipeline_", targets::pipeline),
    ];
    let mut replayed = 0;
    for entry in std::fs::read_dir(&dir).expect("fuzz/findings") {
        let path = entry.expect("a folder entry").path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        if name == "README.md" {
            continue;
        }
        let Some((_, target)) = targets.iter().find(|(p, _)| name.starts_with(p)) else {
            panic!("{name}: no fuzz target for this finding");
        };
        target(&std::fs::read(&path).expect("a finding"));
        replayed += 1;
    }
    assert!(replayed >= 2, "only {replayed} findings replayed");
}
