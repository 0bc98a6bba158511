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
    code: NamedSource<Excerpt>,
    #[label("{label}")]
    span: SourceSpan,
    label: String,
    #[help]
    help: Option<String>,
}

/// Longest line (bytes) kept of a program line shown around a diagnostic; the rest of the line
/// is skipped unread into memory.
const MAX_KEPT_LINE: usize = 16 * 1024;

/// Characters of a program line a snippet shows (a window around the column, with `…` where
/// the line goes on).
const SHOWN_CHARS: usize = klar_interp::MAX_QUOTED_CHARS;

/// Prints each diagnostic to standard error: its plain line, then (for the first few) the
/// snippet.
pub fn print(diags: &[Diagnostic]) {
    let colour = std::io::stderr().is_terminal();
    for (i, d) in diags.iter().enumerate() {
        eprintln!("{d}");
        if i >= MAX_SNIPPETS {
            continue;
        }
        if let Some(lines) = read_excerpt(&d.file, d.line)
            && let Some(s) = draw(d, &lines, colour)
        {
            eprint!("{s}");
        }
    }
}

/// Lines around a diagnostic: the first line's number and the lines (without line ends).
struct Lines {
    first: u32,
    lines: Vec<(String, bool)>,
}

/// The lines `line - 1 ..= line + 1` of a program file, each cut at [`MAX_KEPT_LINE`] bytes
/// (marked true when cut); None when the file is not a regular file or cannot be read. Reads
/// through a fixed buffer: the lines before are skipped whatever their length.
fn read_excerpt(path: &std::path::Path, line: u32) -> Option<Lines> {
    use std::io::BufRead;
    if line == 0 || klar_interp::not_a_file(path).is_some() {
        return None;
    }
    let mut r = std::io::BufReader::new(std::fs::File::open(path).ok()?);
    let first = line.saturating_sub(1).max(1);
    let last = line.saturating_add(1);
    let mut out = Lines {
        first,
        lines: Vec::new(),
    };
    let mut n = 1u32;
    let mut cur: Vec<u8> = Vec::new();
    let mut cut = false;
    loop {
        let buf = r.fill_buf().ok()?;
        if buf.is_empty() {
            if n >= first && n <= last && !cur.is_empty() {
                out.lines.push((decode(&cur, cut), cut));
            }
            break;
        }
        let (take, ends) = match buf.iter().position(|&b| b == b'\n') {
            Some(k) => (k + 1, true),
            None => (buf.len(), false),
        };
        if n >= first && n <= last {
            let room = MAX_KEPT_LINE.saturating_sub(cur.len());
            let part = buf.get(..take.min(room)).unwrap_or(&[]);
            cur.extend_from_slice(part);
            cut |= take > room;
        }
        r.consume(take);
        if ends {
            if n >= first && n <= last {
                while matches!(cur.last(), Some(b'\n' | b'\r')) {
                    cur.pop();
                }
                out.lines.push((decode(&cur, cut), cut));
            }
            cur.clear();
            cut = false;
            n = n.saturating_add(1);
            if n > last {
                break;
            }
        }
    }
    (out.lines.len() as u64 > u64::from(line - first)).then_some(out)
}

/// Text of a program line: UTF-8 when it is (a character cut at the end dropped), latin-1
/// otherwise (older controls write latin-1: every byte is its own code point).
fn decode(bytes: &[u8], cut: bool) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_string(),
        Err(e) if cut && e.error_len().is_none() => {
            String::from_utf8_lossy(bytes.get(..e.valid_up_to()).unwrap_or(&[])).into_owned()
        }
        Err(_) => bytes.iter().map(|&b| b as char).collect(),
    }
}

/// Program lines as miette reads them, numbered from their place in the file.
#[derive(Debug)]
struct Excerpt {
    text: String,
    /// 0-based line of the first line in the file.
    first: usize,
}

impl miette::SourceCode for Excerpt {
    fn read_span<'a>(
        &'a self,
        span: &SourceSpan,
        before: usize,
        after: usize,
    ) -> Result<Box<dyn miette::SpanContents<'a> + 'a>, miette::MietteError> {
        let c = self.text.as_str().read_span(span, before, after)?;
        Ok(Box::new(miette::MietteSpanContents::new(
            c.data(),
            *c.span(),
            c.line() + self.first,
            c.column(),
            c.line_count(),
        )))
    }
}

/// Draws `d` against the whole program text (tests); None when its line is not in the text.
#[cfg(test)]
pub fn snippet(d: &Diagnostic, text: &str, colour: bool) -> Option<String> {
    let line = usize::try_from(d.line.checked_sub(1)?).ok()?;
    let first = line.saturating_sub(1);
    let lines: Vec<(String, bool)> = text
        .split_inclusive('\n')
        .skip(first)
        .take(3)
        .map(|l| (l.trim_end_matches(['\n', '\r']).to_string(), false))
        .collect();
    if lines.len() <= line - first {
        return None;
    }
    draw(
        d,
        &Lines {
            first: u32::try_from(first + 1).ok()?,
            lines,
        },
        colour,
    )
}

/// One line as shown: a window of [`SHOWN_CHARS`] characters from `from`, `…` where it goes
/// on; returns the text and the character offset of `from` in it.
fn window(line: &str, from: usize, cut: bool) -> (String, usize) {
    let mut out = String::new();
    let mut shift = 0;
    if from > 0 {
        out.push('…');
        shift = 1;
    }
    let mut chars = line.chars().skip(from);
    out.extend(chars.by_ref().take(SHOWN_CHARS));
    if chars.next().is_some() || cut {
        out.push('…');
    }
    (out, shift)
}

/// Draws `d` against the lines around it, each shown within [`SHOWN_CHARS`] characters.
fn draw(d: &Diagnostic, lines: &Lines, colour: bool) -> Option<String> {
    let at = usize::try_from(d.line.checked_sub(lines.first)?).ok()?;
    let col0 = usize::try_from(d.col.max(1) - 1).ok()?;
    let mut text = String::new();
    let mut col = 1u32;
    for (k, (l, cut)) in lines.lines.iter().enumerate() {
        let from = if k == at {
            col0.saturating_sub(SHOWN_CHARS / 2).min(l.chars().count())
        } else {
            0
        };
        let (shown, shift) = window(l, from, *cut);
        if k == at {
            col = u32::try_from(col0 - from + shift + 1).ok()?;
        }
        text.push_str(&shown);
        text.push('\n');
    }
    let (span, word) = locate(&text, u32::try_from(at + 1).ok()?, col)?;
    let word = word.to_string();
    let report = Snippet {
        message: d.message.clone(),
        code: NamedSource::new(
            d.file.display().to_string(),
            Excerpt {
                text,
                first: usize::try_from(lines.first).ok()?.saturating_sub(1),
            },
        ),
        span,
        label: if word.is_empty() {
            "here".into()
        } else {
            format!("`{word}`")
        },
        help: suggestion(&d.message, &word),
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
