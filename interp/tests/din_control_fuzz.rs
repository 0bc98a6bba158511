//! Random arrangements of DIN PLUS statements, balanced or not, never panic and always end
//! (run, check and syntax check).

use klar_interp::{Interpreter, Pose};

/// A small deterministic generator (xorshift).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[(self.next() % items.len() as u64) as usize]
    }
}

const LINES: [&str; 25] = [
    "#l1 = 0",
    "#l1 = #l1 + 1",
    "#g1 = #l1 * 2",
    "IF #l1 < 3",
    "IF #g1 == 2 THEN",
    "THEN",
    "ELSE",
    "ENDIF",
    "WHILE #l1 < 4",
    "ENDWHILE",
    "REPEAT",
    "UNTIL #l1 > 2",
    "SWITCH #l1",
    "CASE 1",
    "CASE 2, 3",
    "DEFAULT",
    "BREAK",
    "ENDSWITCH",
    "G0 X#l1 Z1",
    "G0 X(#g1 + 1)",
    "L\"s\" LA#l1",
    "L\"s\" Q50",
    "RETURN",
    "M30",
    "#l1 = #__la",
];

#[test]
fn random_statement_programs_never_panic() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let dir = std::env::temp_dir().join(format!("klar-din-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for case in 0..300 {
        let mut text = String::from("MACHINING\n");
        let n = 1 + rng.next() % 12;
        for k in 0..n {
            text.push_str(&format!("N{k} {}\n", rng.pick(&LINES)));
        }
        text.push_str("END\nSUBPROGRAM \"s\"\n");
        for k in 0..(rng.next() % 4) {
            text.push_str(&format!("N{} {}\n", 100 + k, rng.pick(&LINES)));
        }
        text.push_str("RETURN\n");
        let ops = Interpreter::from_source("f.nc", &text, Pose::ZERO)
            .take(100_000)
            .count();
        assert!(ops < 100_000, "case {case} did not end:\n{text}");
        let path = dir.join(format!("f{case}.nc"));
        std::fs::write(&path, &text).unwrap();
        let _ = klar_interp::check(&path, Pose::ZERO);
        let _ = klar_interp::syntax_check(&path);
        let _ = std::fs::remove_file(&path);
    }
}
