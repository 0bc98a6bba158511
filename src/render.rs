//! Program diagnostics for people: the `file:line:col: message` line (the contract scripts
//! rely on) followed by the source snippet with the offending word underlined and, where the
//! fix is obvious, a suggestion — drawn by miette, in colour only on a terminal.

use klar_interp::Diagnostic;
use miette::{GraphicalReportHandler, GraphicalTheme, NamedSource, SourceSpan};
use std::io::IsTerminal;

/// Diagnostics drawn with a snippet at most; the rest get their plain line only.
const MAX_SNIPPETS: usize = 10;

/// Words of Klartext blocks that a typing slip is checked against (HEIDENHAIN TNC
/// conversational programming: path functions, feeds, compensation, structure).
const KNOWN_WORDS: &[&str] = &[
    "FMAX", "FAUTO", "FZ", "FU", "RL", "RR", "R0", "DR+", "DR-", "IPA", "IZ", "PA", "PR", "CC",
    "LP", "CP", "CT", "CR", "CHF", "RND", "APPR", "DEP", "TOOL", "CALL", "DEF", "BLK", "FORM",
    "BEGIN", "END", "PGM", "CYCL", "LBL", "REP", "STOP", "LEN", "CCA",
];

/// A diagnostic with its source, as miette draws it.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{message}")]
struct Snippet {
    message: String,
    #[source_code]
    code: NamedSource<String>,
    #[label("{label}")]
    span: SourceSpan,
    label: String,
    #[help]
    help: Option<String>,
}

/// Prints each diagnostic to standard error: its plain line, then (for the first few) the
/// snippet.
pub fn print(diags: &[Diagnostic]) {
    let colour = std::io::stderr().is_terminal();
    let mut source: Option<(std::path::PathBuf, Option<String>)> = None;
    for (i, d) in diags.iter().enumerate() {
        eprintln!("{d}");
        if i >= MAX_SNIPPETS {
            continue;
        }
        if source.as_ref().is_none_or(|(p, _)| *p != d.file) {
            source = Some((d.file.clone(), read_text(&d.file)));
        }
        if let Some((_, Some(text))) = &source
            && let Some(s) = snippet(d, text, colour)
        {
            eprint!("{s}");
        }
    }
}

fn read_text(path: &std::path::Path) -> Option<String> {
    let bytes = std::fs::read(path).ok()?;
    Some(match String::from_utf8(bytes) {
        Ok(s) => s,
        // Older controls write latin-1: every byte is its own code point.
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    })
}

/// Draws `d` against the program text; None when its line is not in the text.
pub fn snippet(d: &Diagnostic, text: &str, colour: bool) -> Option<String> {
    let (span, word) = locate(text, d.line, d.col)?;
    let report = Snippet {
        message: d.message.clone(),
        code: NamedSource::new(d.file.display().to_string(), text.to_string()),
        span,
        label: if word.is_empty() {
            "here".into()
        } else {
            format!("`{word}`")
        },
        help: suggestion(&d.message, word),
    };
    let theme = if colour {
        GraphicalTheme::unicode()
    } else {
        GraphicalTheme::unicode_nocolor()
    };
    let mut out = String::new();
    GraphicalReportHandler::new_themed(theme)
        .with_context_lines(1)
        .render_report(&mut out, &report)
        .ok()?;
    Some(out)
}

/// The byte span of the word at `line`:`col` (1-based, col in characters) and the word; at
/// column 1 the whole block (the line up to a `;` comment).
fn locate(text: &str, line: u32, col: u32) -> Option<(SourceSpan, &str)> {
    let line_idx = usize::try_from(line.checked_sub(1)?).ok()?;
    let mut offset = 0;
    let mut this = None;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i == line_idx {
            this = Some(l.trim_end_matches(['\n', '\r']));
            break;
        }
        offset += l.len();
    }
    let l = this?;
    let col = usize::try_from(col.max(1) - 1).ok()?;
    let start = l.char_indices().nth(col).map_or(l.len(), |(b, _)| b);
    let rest = &l[start..];
    let word = if col == 0 {
        rest.split(';').next().unwrap_or("").trim_end()
    } else {
        let end = rest
            .find(|c: char| c.is_whitespace() || c == ';')
            .unwrap_or(rest.len());
        &rest[..end]
    };
    Some(((offset + start, word.len().max(1)).into(), word))
}

/// A suggestion where the fix is obvious: a known word one slip away, or the radius an arc
/// through the given end points needs.
fn suggestion(message: &str, word: &str) -> Option<String> {
    if message.contains("unknown word") {
        let quoted = message.split('\'').nth(1).unwrap_or(word);
        let upper = quoted.to_ascii_uppercase();
        let best = KNOWN_WORDS
            .iter()
            .map(|k| (edit_distance(&upper, k), *k))
            .filter(|(d, k)| *d <= 1 || (*d == 2 && k.len() >= 5))
            .min_by_key(|(d, _)| *d)?;
        return Some(format!("did you mean `{}`?", best.1));
    }
    if let Some(rest) = message.split("chord ").nth(1)
        && message.contains("longer than 2R")
    {
        let chord: f64 = rest.split_whitespace().next()?.parse().ok()?;
        return Some(format!(
            "an arc through these end points needs a radius of at least {:.3} mm",
            chord / 2.0
        ));
    }
    None
}

/// Levenshtein distance between two short words.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn diag(line: u32, col: u32, message: &str) -> Diagnostic {
        Diagnostic {
            file: "t.h".into(),
            line,
            col,
            block: None,
            message: message.into(),
        }
    }

    #[test]
    fn the_offending_word_is_underlined_with_a_suggestion() {
        let text = "0 BEGIN PGM T MM\n6 L X+5 FMX ; slip\n7 END PGM T MM\n";
        let d = diag(2, 9, "block 6: unknown word 'FMX' in L block");
        let out = snippet(&d, text, false).unwrap();
        assert!(out.contains("6 L X+5 FMX ; slip"), "{out}");
        assert!(out.contains("did you mean `FMAX`?"), "{out}");
        // The underline starts under column 9 and is three characters long.
        let src = out.lines().find(|l| l.contains("6 L X+5 FMX")).unwrap();
        let mark = out
            .lines()
            .skip_while(|l| !l.contains("6 L X+5 FMX"))
            .nth(1)
            .unwrap();
        let at = src.find("FMX").unwrap();
        let under: String = mark.chars().skip(at).take(3).collect();
        assert!(under.chars().all(|c| "─┬▲^".contains(c)), "{mark:?}");
    }

    #[test]
    fn a_too_short_radius_gets_the_needed_one() {
        let text = "0 BEGIN PGM T MM\n1 CR X+50 Y+0 R+10 DR+\n";
        let d = diag(
            2,
            1,
            "block 1: CR chord 45.000 mm longer than 2R = 20.000 mm",
        );
        let out = snippet(&d, text, false).unwrap();
        assert!(out.contains("radius of at least 22.500 mm"), "{out}");
    }

    #[test]
    fn no_suggestion_for_words_far_from_any_known_one() {
        assert_eq!(suggestion("unknown word 'QQ' in L block", "QQ7"), None);
        assert_eq!(edit_distance("FMX", "FMAX"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn positions_outside_the_text_draw_nothing() {
        assert!(snippet(&diag(9, 1, "x"), "one line\n", false).is_none());
        assert!(snippet(&diag(0, 1, "x"), "one line\n", false).is_none());
        // A column past the end of the line marks the line's end.
        assert!(snippet(&diag(1, 99, "x"), "one line\n", false).is_some());
    }
}
