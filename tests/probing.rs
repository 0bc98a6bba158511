//! Touch-probe cycles on the simulated machine with a part set up off its nominal place.

mod common;

use klar::config::MachineConfig;
use std::path::{Path, PathBuf};

fn machine() -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/probing-mill.toml");
    MachineConfig::load(&p).expect("probing machine loads")
}

fn run_q(path: &PathBuf) -> klar_interp::Interpreter {
    let m = machine();
    let mut it = m.open_program(path, m.start_pose()).expect("opens");
    for op in it.by_ref() {
        op.expect("runs");
    }
    it
}

#[test]
fn debug412() {
    let it = run_q(&common::program("probing_412.h"));
    for q in [151, 152, 153] {
        eprintln!("Q{q} = {}", it.q(q));
    }
}
