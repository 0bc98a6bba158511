//! Interpreter throughput and streaming memory.
//!
//! `interpret_1m_blocks`: a generated Klartext program of one million L/CC/C/CR/LP blocks
//! with Q-parameter words and formulas, interpreted in full from memory (throughput in
//! blocks/s; each run also prints its CPU time, which stays meaningful on a loaded machine). `stream_10m_blocks_from_file`: ten million blocks streamed from a temporary
//! file; a counting global allocator records the peak heap use, printed after the run.
//! `syntax_check_1m_blocks`: the parse-only pass of `syntax_check` over a 1M-block file.
//! `refuse_64mb_line`: a program whose third line is 64 MB without a line end, interpreted
//! until the block-length error; the peak heap is printed (bounded by the block limit, not by
//! the line).

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicUsize, Ordering};

use klar_interp::{Interpreter, Pose};

/// Counts live heap bytes and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn note_alloc(size: usize) {
    let live = LIVE.fetch_add(size, Ordering::Relaxed) + size;
    PEAK.fetch_max(live, Ordering::Relaxed);
}

// SAFETY: every call is forwarded unchanged to the system allocator; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note_alloc(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        note_alloc(new_size);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// The repeating body: 8 blocks that return to their start, so any count can be generated.
const BODY: [&str; 8] = [
    "L X+Q1 Y+Q2 F500",
    "CC X+0 Y+0",
    "C X+0 Y+10 DR+",
    "CR X-10 Y+0 R+10 DR+",
    "LP PR+10 PA+270",
    "Q3 = Q3 + 0.001",
    "L X+Q1 Y-Q2 Z-Q3 FQ4",
    "L IX+0.5 IY+0 M8",
];

/// Writes a program of `blocks` blocks (BEGIN and END included) to `out`.
fn generate(blocks: u64, out: &mut impl Write) -> std::io::Result<()> {
    writeln!(out, "0 BEGIN PGM BENCH MM")?;
    writeln!(out, "1 Q1 = 10")?;
    writeln!(out, "2 Q2 = 0")?;
    writeln!(out, "3 FN 0: Q4 = +800")?;
    let mut n = 4;
    while n < blocks - 1 {
        writeln!(out, "{n} {}", BODY[((n - 4) % 8) as usize])?;
        n += 1;
    }
    writeln!(out, "{n} END PGM BENCH MM")
}

fn program_text(blocks: u64) -> String {
    let mut v = Vec::with_capacity(blocks as usize * 24);
    generate(blocks, &mut v).expect("in-memory write");
    String::from_utf8(v).expect("ASCII")
}

const ONE_MILLION: u64 = 1_000_000;

/// Nanoseconds this thread has spent on a CPU (Linux `/proc/thread-self/schedstat`), so that
/// throughput can also be stated independently of other load on a shared machine.
fn cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn interpret_1m_blocks(bencher: divan::Bencher) {
    let text = program_text(ONE_MILLION);
    bencher
        .counter(divan::counter::ItemsCount::new(ONE_MILLION))
        .bench_local(|| {
            let cpu0 = cpu_ns();
            let mut it = Interpreter::from_source("bench.h", &text, Pose::ZERO);
            let mut ops = 0u64;
            for r in it.by_ref() {
                if r.is_err() {
                    panic!("benchmark program failed: {r:?}");
                }
                ops += 1;
            }
            assert_eq!(it.blocks_executed(), ONE_MILLION);
            if let (Some(a), Some(b)) = (cpu0, cpu_ns()) {
                let secs = (b - a) as f64 / 1e9;
                println!(
                    "interpret 1M blocks: {:.3} s on CPU = {:.2} M blocks/s CPU time",
                    secs,
                    ONE_MILLION as f64 / secs / 1e6
                );
            }
            ops
        });
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn syntax_check_1m_blocks(bencher: divan::Bencher) {
    let path = std::env::temp_dir().join(format!("klar-bench-syntax-{}.h", std::process::id()));
    {
        let f = std::fs::File::create(&path).expect("temp file");
        let mut w = std::io::BufWriter::new(f);
        generate(ONE_MILLION, &mut w).expect("write program");
        w.flush().expect("flush");
    }
    bencher
        .counter(divan::counter::ItemsCount::new(ONE_MILLION))
        .bench_local(|| klar_interp::syntax_check(&path).is_ok());
    let _ = std::fs::remove_file(&path);
}

const TEN_MILLION: u64 = 10_000_000;

#[divan::bench(sample_count = 1, sample_size = 1)]
fn stream_10m_blocks_from_file(bencher: divan::Bencher) {
    let path = std::env::temp_dir().join(format!("klar-bench-{}.h", std::process::id()));
    {
        let f = std::fs::File::create(&path).expect("temp file");
        let mut w = std::io::BufWriter::new(f);
        generate(TEN_MILLION, &mut w).expect("write program");
        w.flush().expect("flush");
    }
    bencher
        .counter(divan::counter::ItemsCount::new(TEN_MILLION))
        .bench_local(|| {
            let base = LIVE.load(Ordering::Relaxed);
            PEAK.store(base, Ordering::Relaxed);
            let mut it = Interpreter::open(&path, Pose::ZERO).expect("open");
            let mut ops = 0u64;
            for r in it.by_ref() {
                if r.is_err() {
                    panic!("benchmark program failed: {r:?}");
                }
                ops += 1;
            }
            assert_eq!(it.blocks_executed(), TEN_MILLION);
            drop(it);
            let peak = PEAK.load(Ordering::Relaxed) - base;
            println!(
                "stream 10M blocks: {ops} ops, peak heap while streaming {:.3} MB",
                peak as f64 / 1e6
            );
            ops
        });
    let _ = std::fs::remove_file(&path);
}

#[divan::bench(sample_count = 3, sample_size = 1)]
fn refuse_64mb_line(bencher: divan::Bencher) {
    let path = std::env::temp_dir().join(format!("klar-bench-line-{}.h", std::process::id()));
    {
        let f = std::fs::File::create(&path).expect("temp file");
        let mut w = std::io::BufWriter::new(f);
        w.write_all(b"0 BEGIN PGM T MM\n1 L X+0 R0 FMAX\n")
            .expect("write program");
        let piece = vec![b'X'; 1 << 20];
        for _ in 0..64 {
            w.write_all(&piece).expect("write program");
        }
        w.flush().expect("flush");
    }
    bencher.bench_local(|| {
        let base = LIVE.load(Ordering::Relaxed);
        PEAK.store(base, Ordering::Relaxed);
        let it = Interpreter::open(&path, Pose::ZERO).expect("open");
        let errors = it.filter(Result::is_err).count();
        assert_eq!(errors, 1);
        let peak = PEAK.load(Ordering::Relaxed) - base;
        println!("refuse a 64 MB line: peak heap {:.3} MB", peak as f64 / 1e6);
        errors
    });
    let _ = std::fs::remove_file(&path);
}

fn main() {
    divan::main();
}
