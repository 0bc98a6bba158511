//! Whole-program checks built on the interpreter: syntax only, or a run without motion that
//! reports every error.

use std::path::Path;

use super::{CHECK_DIAGNOSTIC_LIMIT, Interpreter, Mode};
use crate::diag::Diagnostic;
use crate::op::Pose;

impl Interpreter {
    /// Runs to the end in `mode`, collecting every diagnostic.
    pub(super) fn run_all(&mut self, mode: Mode) -> Vec<Diagnostic> {
        if let Some(o) = &mut self.other {
            return o.check_all(mode == Mode::Syntax);
        }
        let mut diags = Vec::new();
        while !self.done {
            let r = self.step(mode);
            if mode == Mode::Check && self.depends_on.is_none() && self.machine.operator_value {
                self.depends_on = Some(format!(
                    "the position read at line {} after a program stop",
                    self.current.line
                ));
            }
            if let Err(mut d) = r {
                let jump_limit = d.message.contains("jumps: the check stops");
                if let Some(why) = &self.depends_on {
                    // values that depend on the machine are only known when the program runs
                    d.message = format!("{} (depends on {why})", d.message);
                    self.undecided.push(d);
                    if self.undecided.len() >= CHECK_DIAGNOSTIC_LIMIT {
                        break;
                    }
                    continue;
                }
                diags.push(d);
                if diags.len() >= CHECK_DIAGNOSTIC_LIMIT || jump_limit {
                    break;
                }
            }
            while self.pop_ready().is_some() {}
        }
        diags
    }
}

/// Checks a program's syntax in one streaming pass without executing it (constant memory).
///
/// Reports every syntax error: unknown or misplaced words, missing values, a missing BEGIN PGM
/// or END PGM, blocks after END PGM.
pub fn syntax_check(path: &Path) -> Result<(), Vec<Diagnostic>> {
    let mut it = Interpreter::open(path, Pose::ZERO).map_err(|d| vec![d])?;
    let diags = it.run_all(Mode::Syntax);
    if diags.is_empty() { Ok(()) } else { Err(diags) }
}

/// Checks syntax and runs the program without motion, reporting all errors (geometry and
/// runtime errors included); a block with an error is skipped and the run goes on.
///
/// Files the program reads that are not there (a called program, a table) count as errors
/// here; [`check_report`] tells them apart.
pub fn check(path: &Path, start: Pose) -> Vec<Diagnostic> {
    let r = check_report(path, start);
    let mut all = r.errors;
    all.extend(r.missing);
    all.sort_by_key(|d| d.line);
    all
}

/// What a check run found: errors, and what cannot be decided before the program runs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CheckReport {
    /// Errors: the program is refused.
    pub errors: Vec<Diagnostic>,
    /// Files the program reads that are not beside it (a called program, a table): the
    /// check of this file goes on past them, a run stops there. A test run against a machine
    /// refuses them.
    pub missing: Vec<Diagnostic>,
    /// Problems that depend on what happens at the machine: errors that follow from positions
    /// read (FN 18 ID240/ID270) after a program stop, where the operator may have moved the
    /// axes, or from a missing file's data.
    pub undecided: Vec<Diagnostic>,
    /// Forms accepted with leniency: the program runs, but not as written (see
    /// [`Interpreter::warnings`]).
    pub warnings: Vec<Diagnostic>,
}

/// [`check`] with what it could not decide before the run.
pub fn check_report(path: &Path, start: Pose) -> CheckReport {
    match Interpreter::open(path, start) {
        Ok(it) => it.check_report(),
        Err(d) => CheckReport {
            errors: vec![d],
            ..CheckReport::default()
        },
    }
}

impl Interpreter {
    /// Runs the whole program as a check (no file is written; every error is reported, a
    /// block with an error is skipped) with this interpreter's tools and machine settings.
    pub fn check_report(mut self) -> CheckReport {
        self.set_dry_run(true);
        // A check keeps no coordinates: compensation in a tilted plane is allowed as in a run.
        self.set_working_plane_ops(true);
        let errors = fold_repeats(self.run_all(Mode::Check));
        CheckReport {
            errors,
            missing: std::mem::take(&mut self.missing),
            undecided: std::mem::take(&mut self.undecided),
            warnings: std::mem::take(&mut self.warnings),
        }
    }
}

/// One error and its consequences are one diagnostic: a run of errors with the same message
/// in the same file (every block after a missing feed, say) becomes the first of them, which
/// names the lines of the others.
fn fold_repeats(errors: Vec<Diagnostic>) -> Vec<Diagnostic> {
    /// The message without its `block N: ` prefix.
    fn without_block(m: &str) -> &str {
        match m.strip_prefix("block ").and_then(|r| r.split_once(": ")) {
            Some((n, rest)) if n.bytes().all(|b| b.is_ascii_digit()) => rest,
            _ => m,
        }
    }
    let mut out: Vec<(Diagnostic, Vec<u32>)> = Vec::with_capacity(errors.len());
    for d in errors {
        match out.last_mut() {
            Some((first, more))
                if without_block(&first.message) == without_block(&d.message)
                    && first.file == d.file =>
            {
                more.push(d.line);
            }
            _ => out.push((d, Vec::new())),
        }
    }
    out.into_iter()
        .map(|(mut d, more)| {
            match more.as_slice() {
                [] => {}
                [one] => d.message = format!("{} (also line {one})", d.message),
                [first, .., last] if more.len() > 3 => {
                    d.message = format!(
                        "{} (also {} more lines, {first} to {last})",
                        d.message,
                        more.len()
                    )
                }
                lines => {
                    let list: Vec<String> = lines.iter().map(u32::to_string).collect();
                    d.message = format!("{} (also lines {})", d.message, list.join(", "));
                }
            }
            d
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::io::Cursor;
    use std::path::PathBuf;

    #[test]
    fn repeated_consequences_are_one_diagnostic() {
        let text = "BEGIN PGM F MM\nL X+0 Y+0 Z+50 R0 FMAX\nL X+10\nL X+20\nL X+30\n\
                    L Y+5 F100\nL X+10 Y+10 Z+10 Q\nEND PGM F MM\n";
        let report = Interpreter::from_source("f.h", text, Pose::ZERO).check_report();
        let lines: Vec<u32> = report.errors.iter().map(|d| d.line).collect();
        assert_eq!(lines.first(), Some(&3), "{:?}", report.errors);
        let first = &report.errors[0].message;
        assert!(first.ends_with("(also lines 4, 5)"), "{first}");
        // a different error later is still reported on its own
        assert_eq!(lines.len(), 2, "{:?}", report.errors);
    }

    fn run_bytes(bytes: Vec<u8>, mode: Mode) -> usize {
        let mut it = Interpreter::with_input(
            PathBuf::from("fuzz.h"),
            Box::new(Cursor::new(bytes)),
            Pose::ZERO,
        );
        match mode {
            Mode::Run => it.by_ref().take(10_000).count(),
            other => it.run_all(other).len(),
        }
    }

    proptest! {
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            run_bytes(bytes.clone(), Mode::Run);
            run_bytes(bytes.clone(), Mode::Check);
            run_bytes(bytes, Mode::Syntax);
        }

        #[test]
        fn random_blocks_after_begin_never_panic(
            body in proptest::collection::vec(any::<u8>(), 0..300)
        ) {
            let mut bytes = b"BEGIN PGM F MM\nCC X+0 Y+0\nL X+5 F100\n".to_vec();
            bytes.extend_from_slice(&body);
            run_bytes(bytes.clone(), Mode::Run);
            run_bytes(bytes, Mode::Check);
        }
    }
}
