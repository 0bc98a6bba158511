//! Near-valid Klartext: words and blocks recombined at random must give ops or diagnostics,
//! never a panic, and diagnostics must point inside the text.

use klar_interp::{Interpreter, Pose};
use proptest::prelude::*;

const PIECES: &[&str] = &[
    "L",
    "LP",
    "C",
    "CC",
    "CR",
    "CT",
    "CP",
    "X+10",
    "Y-5",
    "Z",
    "IX+2,5",
    "IPA+720",
    "PA-90",
    "PR+5",
    "IPR",
    "DR+",
    "DR-",
    "DR",
    "R+10",
    "R-3",
    "R0",
    "RL",
    "RR",
    "R",
    "F100",
    "FMAX",
    "F MAX",
    "F",
    "FQ1",
    "M3",
    "M30",
    "M",
    "M999",
    "Q1 =",
    "Q1",
    "QL2",
    "-Q1",
    "+",
    "-",
    "*",
    "/",
    "^",
    "(",
    ")",
    "SIN",
    "SQRT",
    "FN 0:",
    "FN 4:",
    "DIV",
    "TOOL CALL",
    "1",
    "Z",
    "S3000",
    "DL+0.1",
    "DR-Q108",
    ";",
    "~\n",
    "\n",
    " ",
    "*",
    "/",
    "N5",
    "0.1",
    "BLK FORM",
    "BEGIN PGM",
    "END PGM",
    "MM",
    "INCH",
    "\"",
    "{0:+d}",
    "\u{e4}",
    "99999999999999999999",
    "1e5",
    "IZ-2",
];

fn pieces() -> impl Strategy<Value = String> {
    proptest::collection::vec(proptest::sample::select(PIECES), 0..60).prop_map(|v| v.join(" "))
}

proptest! {
    #[test]
    fn recombined_words_never_panic(body in pieces()) {
        let text = format!("BEGIN PGM F MM\nCC X+0 Y+0\nL X+5 Y+0 F100\n{body}\nEND PGM F MM\n");
        let lines = text.lines().count() as u32 + 1;
        for r in Interpreter::from_source("f.h", &text, Pose::ZERO).take(100_000) {
            if let Err(d) = r {
                prop_assert!(d.line >= 1 && d.line <= lines, "{d}");
                prop_assert!(d.col >= 1, "{d}");
            }
        }
    }
}

/// One coordinate word: (letter, incremental, value or parameter number, is parameter).
fn coord() -> impl Strategy<Value = (char, bool, f64, bool)> {
    (
        proptest::sample::select(vec!['X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W']),
        any::<bool>(),
        -99_999.999_9_f64..99_999.999_9,
        any::<bool>(),
    )
}

proptest! {
    /// Compact words (`IX-12.5`, `Y+Q3`) take the lexer's fast path; the same words with
    /// spaces inside (`IX - 12.5`) go through the general token path. Both must give the
    /// same ops.
    #[test]
    fn compact_and_spaced_words_agree(
        words in proptest::collection::vec(coord(), 1..6),
        feed in 1u32..100_000,
    ) {
        // `7 L` takes the plain block-start path, `N7 L` the token path
        let mut compact = String::from("7 L");
        let mut spaced = String::from("N7 L");
        let mut seen = std::collections::HashSet::new();
        for (letter, inc, v, param) in words {
            if !seen.insert(letter) {
                continue;
            }
            let i = if inc { "I" } else { "" };
            let sign = if v < 0.0 { '-' } else { '+' };
            let body = if param {
                format!("Q{}", (v.abs() as u32) % 100)
            } else {
                format!("{:.4}", v.abs())
            };
            compact.push_str(&format!(" {i}{letter}{sign}{body}"));
            spaced.push_str(&format!(" {i}{letter} {sign} {}", body.replace('Q', "Q ")));
        }
        compact.push_str(&format!(" F{feed}"));
        spaced.push_str(&format!(" F {feed}"));
        let setup = "Q1 = 1.5\nQ7 = -20\nQ42 = 1000\nL X+1 Y+2 Z+3 A+4 B+5 C+6 U+7 V+8 W+9 F100";
        let run = |block: &str| -> Vec<_> {
            let text = format!("BEGIN PGM P MM\n{setup}\n{block}\nEND PGM P MM\n");
            Interpreter::from_source("p.h", &text, Pose::ZERO)
                .map(|r| r.map(|op| op.kind).map_err(|d| d.message))
                .collect()
        };
        prop_assert_eq!(run(&compact), run(&spaced));
    }
}

proptest! {
    /// Polar, direction, compensation and M words: compact (fast path) and spaced (token
    /// path) spellings give the same ops.
    #[test]
    fn compact_and_spaced_polar_words_agree(
        pr in 0.5f64..500.0,
        pa in -360.0f64..360.0,
        ipa in 1.0f64..2000.0,
        ccw in any::<bool>(),
        m in proptest::sample::select(vec![3u32, 5, 8, 9, 13, 14, 91]),
        rl in any::<bool>(),
    ) {
        let d = if ccw { '+' } else { '-' };
        let c = if rl { "RL" } else { "RR" };
        let compact = format!(
            "7 LP PR+{pr:.4} PA{pa:+.4} {c} FMAX M{m}\n8 CP IPA{d}{ipa:.4} IZ-1 DR{d} F200"
        );
        let spaced = format!(
            "N7 LP PR + {pr:.4} PA {} {:.4} {c} F MAX M {m}\nN8 CP IPA {d} {ipa:.4} IZ - 1 DR {d} F 200",
            if pa < 0.0 { '-' } else { '+' },
            pa.abs()
        );
        let run = |block: &str| -> Vec<_> {
            let text = format!("BEGIN PGM P MM\nCC X+0 Y+0\nL X+1 F100\n{block}\nEND PGM P MM\n");
            Interpreter::from_source("p.h", &text, Pose::ZERO)
                .map(|r| r.map(|op| op.kind).map_err(|d| d.message))
                .collect()
        };
        prop_assert_eq!(run(&compact), run(&spaced));
    }
}
