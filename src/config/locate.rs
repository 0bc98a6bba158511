//! Where in a machine file an error lies: the line and column of the key a message names.
//!
//! The TOML parser reports the line of a syntax error, but a value error found after parsing
//! (a negative velocity, travel min above max) and an unknown key inside a table that names
//! its backend by `kind` reach the user without one, or with the line of the table header.
//! This module finds the key in the text so every message can say `file:line:col:`.
//!
//! Messages of [`MachineConfig::validate`](super::MachineConfig) name their key in one of
//! these forms, and [`locate`] reads them back:
//! - `axis X: KEY …`: the key within the `[[axis]]` entry with `letter = "X"`;
//! - `axis X is defined twice`: the `letter` line of its second entry;
//! - `spindle.KEY …`, `table_table.KEY …`: the key in that table (and its sub-tables);
//! - `spindle: …` and `spindle simulation KEY`: a key of the spindle's tables;
//! - `fault Kind: KEY …`, `m_function MN: KEY …`: the key of that `[[fault]]` /
//!   `[[m_function]]` entry;
//! - otherwise the first word when it is a key at the top of the file.
//!
//! A key that cannot be found leaves the message without a place: the message itself still
//! names what is wrong.

/// One `[table]` or `[[array]]` section of the file: its name and its lines.
struct Section<'a> {
    /// The dotted name in the header; empty for the keys before the first header.
    name: &'a str,
    /// True for `[[name]]`.
    array: bool,
    /// 0-based index of the first line after the header (the header's own line for the top).
    first: usize,
    /// 0-based index one past the last line.
    end: usize,
}

fn sections<'a>(lines: &'a [&'a str]) -> Vec<Section<'a>> {
    let mut out = vec![Section {
        name: "",
        array: false,
        first: 0,
        end: lines.len(),
    }];
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim_start();
        let (array, inner) = if let Some(r) = t.strip_prefix("[[") {
            (true, r.split("]]").next())
        } else if let Some(r) = t.strip_prefix('[') {
            (false, r.split(']').next())
        } else {
            continue;
        };
        let Some(name) = inner.map(str::trim) else {
            continue;
        };
        if let Some(last) = out.last_mut() {
            last.end = i;
        }
        out.push(Section {
            name,
            array,
            first: i + 1,
            end: lines.len(),
        });
    }
    out
}

/// The column (0-based byte) of `key` written as a key (`key =` / `key=`) in `line`, also
/// inside an inline table.
fn key_in(line: &str, key: &str) -> Option<usize> {
    let code = line.split('#').next().unwrap_or("");
    let bytes = code.as_bytes();
    let mut from = 0;
    while let Some(off) = code.get(from..).and_then(|s| s.find(key)) {
        let at = from + off;
        let before_ok = at == 0
            || bytes
                .get(at - 1)
                .is_some_and(|b| !(b.is_ascii_alphanumeric() || *b == b'_'));
        let after = code.get(at + key.len()..).unwrap_or("");
        if before_ok && after.trim_start().starts_with('=') {
            return Some(at);
        }
        from = at + key.len();
    }
    None
}

/// The value of `key` in the lines `range` as written (quotes removed), e.g. an axis letter.
fn value_in(lines: &[&str], range: std::ops::Range<usize>, key: &str) -> Option<String> {
    lines.get(range)?.iter().find_map(|line| {
        let col = key_in(line, key)?;
        let rest = line
            .get(col + key.len()..)?
            .trim_start()
            .strip_prefix('=')?;
        let v = rest.split(['#', ',', '}']).next()?.trim();
        Some(v.trim_matches(['"', '\'']).to_string())
    })
}

/// One entry of an array of tables: its header's section index and the line range of the
/// entry including its sub-tables.
fn entries<'a>(secs: &'a [Section<'a>], root: &str) -> Vec<std::ops::Range<usize>> {
    let mut out: Vec<std::ops::Range<usize>> = Vec::new();
    for s in secs {
        let top = s.name.split('.').next().unwrap_or("").trim();
        if top != root {
            continue;
        }
        if s.array && s.name == root {
            out.push(s.first..s.end);
        } else if let Some(last) = out.last_mut() {
            last.end = s.end;
        } else {
            out.push(s.first..s.end);
        }
    }
    out
}

/// The 1-based line and column of `key` within `range`; the line before the range (its
/// header) when the key is not there.
fn key_or_header(
    lines: &[&str],
    range: std::ops::Range<usize>,
    key: Option<&str>,
) -> Option<(usize, usize)> {
    if let Some(key) = key {
        for i in range.clone() {
            if let Some(col) = lines.get(i).and_then(|l| key_in(l, key)) {
                return Some((i + 1, col + 1));
            }
        }
    }
    // the header line of the entry (the section starts after it)
    (range.start > 0).then_some((range.start, 1))
}

/// The key a message names after `prefix: ` — its first word when that is a key.
fn first_word(rest: &str) -> Option<&str> {
    let w = rest
        .trim_start()
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .next()?;
    (!w.is_empty()).then_some(w)
}

/// The 1-based line and column in `text` of the key `message` names, if it can be found.
pub(super) fn locate(text: &str, message: &str) -> Option<(usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let secs = sections(&lines);
    let in_table = |name: &str, key: Option<&str>| {
        let range = secs
            .iter()
            .filter(|s| s.name == name || s.name.starts_with(&format!("{name}.")))
            .map(|s| s.first..s.end)
            .reduce(|a, b| a.start..b.end.max(a.end))?;
        key_or_header(&lines, range, key)
    };
    let in_entry = |root: &str, field: &str, wanted: &str, key: Option<&str>, nth: usize| {
        let range = entries(&secs, root)
            .into_iter()
            .filter(|r| {
                value_in(&lines, r.clone(), field).is_some_and(|v| v.eq_ignore_ascii_case(wanted))
            })
            .nth(nth)?;
        key_or_header(&lines, range, key)
    };
    if let Some(rest) = message.strip_prefix("axis ") {
        let letter = rest.get(..1)?;
        let after = rest.get(1..)?;
        if after.starts_with(" is defined twice") {
            return in_entry("axis", "letter", letter, Some("letter"), 1);
        }
        let key = if after.starts_with(": no [canopen.") {
            Some("bus")
        } else {
            after.strip_prefix(':').and_then(first_word)
        };
        return in_entry("axis", "letter", letter, key, 0);
    }
    if let Some(rest) = message.strip_prefix("fault ") {
        let kind = first_word(rest)?;
        let key = rest.split_once(':').and_then(|(_, r)| first_word(r));
        return in_entry("fault", "kind", kind, key, 0);
    }
    if let Some(rest) = message.strip_prefix("m_function M") {
        let number = first_word(rest)?;
        let key = rest.split_once(':').and_then(|(_, r)| first_word(r));
        return in_entry("m_function", "number", number, key, 0);
    }
    for table in ["spindle", "table_table"] {
        if let Some(rest) = message.strip_prefix(table) {
            let key = if let Some(r) = rest.strip_prefix('.') {
                first_word(r)
            } else if let Some(r) = rest.strip_prefix(" simulation ") {
                first_word(r)
            } else if rest.starts_with(": no [canopen.") {
                Some("bus")
            } else {
                None
            };
            return in_table(table, key);
        }
    }
    let word = first_word(message)?;
    let top = secs.first()?;
    (top.first..top.end).find_map(|i| {
        let col = lines.get(i).and_then(|l| key_in(l, word))?;
        Some((i + 1, col + 1))
    })
}

/// The key most like `unknown` among `known` (at most a third of its letters differ), for a
/// "did you mean" hint.
pub(super) fn closest<'a>(unknown: &str, known: &[&'a str]) -> Option<&'a str> {
    let best = known
        .iter()
        .map(|k| (edit_distance(unknown, k), *k))
        .min_by_key(|(d, _)| *d)?;
    (best.0 > 0 && best.0 <= unknown.chars().count().div_ceil(3)).then_some(best.1)
}

/// Levenshtein distance (insert, delete, substitute one character).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row.first().copied().unwrap_or(0);
        if let Some(first) = row.first_mut() {
            *first = i + 1;
        }
        for (j, cb) in b.iter().enumerate() {
            let above = row.get(j + 1).copied().unwrap_or(0);
            let left = row.get(j).copied().unwrap_or(0);
            let cost = usize::from(ca != *cb);
            let v = (prev + cost).min(above + 1).min(left + 1);
            prev = above;
            if let Some(slot) = row.get_mut(j + 1) {
                *slot = v;
            }
        }
    }
    row.last().copied().unwrap_or(0)
}

/// Makes the TOML parser's message for an unknown key point at the key instead of the
/// header of its table (the parser reports tables that name their backend by `kind` at
/// their header), and adds the nearest known key as a hint: the place of the key and the new
/// message. Other messages pass unchanged, without a place.
pub(super) fn unknown_key(text: &str, message: &str) -> (Option<(usize, usize)>, String) {
    let unchanged = || (None, message.to_string());
    if let Some(refined) = invalid_value(text, message) {
        return refined;
    }
    let Some((_, after)) = message.split_once("unknown field `") else {
        return unchanged();
    };
    let Some((field, rest)) = after.split_once('`') else {
        return unchanged();
    };
    let known: Vec<&str> = rest
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|s| !s.is_empty())
        .collect();
    let place = find_from(text, reported_line(message), |l| key_in(l, field));
    let hint = closest(field, &known)
        .map(|k| format!(" — did you mean `{k}`?"))
        .unwrap_or_default();
    let expected = if known.is_empty() {
        String::new()
    } else {
        format!(
            " (known here: {})",
            known
                .iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    match place {
        Some(at) => (Some(at), format!("unknown key `{field}`{hint}{expected}")),
        None => (None, format!("{}{hint}", message.trim_end())),
    }
}

/// The line the TOML parser reports an error at (1 when it gives none).
fn reported_line(message: &str) -> usize {
    message
        .strip_prefix("TOML parse error at line ")
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse::<usize>().ok())
        .unwrap_or(1)
}

/// The 1-based line and column of the first key from line `reported` on (before the next
/// table header) for which `hit` holds.
fn find_from(
    text: &str,
    reported: usize,
    hit: impl Fn(&str) -> Option<usize>,
) -> Option<(usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    (reported.saturating_sub(1)..lines.len())
        .take_while(|&i| {
            i + 1 == reported
                || !lines
                    .get(i)
                    .is_some_and(|l| l.trim_start().starts_with('['))
        })
        .find_map(|i| lines.get(i).and_then(|l| hit(l)).map(|c| (i + 1, c + 1)))
}

/// A value of the wrong type in a table the parser reports at its header (`invalid type:
/// string "fast", expected f64`): the place of the key that holds that value.
fn invalid_value(text: &str, message: &str) -> Option<(Option<(usize, usize)>, String)> {
    let (_, after) = message.split_once("invalid type: ")?;
    let what = after.lines().next()?.trim();
    // the literal as the message quotes it: "text" for strings, `5` for other values
    let written = if let Some((_, r)) = what.split_once('"') {
        format!("\"{}\"", r.split('"').next()?)
    } else {
        let (_, r) = what.split_once('`')?;
        r.split('`').next()?.to_string()
    };
    let at = find_from(text, reported_line(message), |line| {
        let code = line.split('#').next().unwrap_or("");
        let (key, value) = code.split_once('=')?;
        (value.trim() == written)
            .then(|| code.len() - code.trim_start().len() + key.len() - key.trim_start().len())
    })?;
    let key = text
        .lines()
        .nth(at.0 - 1)
        .and_then(|l| l.split('=').next())
        .map(str::trim)
        .unwrap_or("value");
    Some((Some(at), format!("{key}: invalid type: {what}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "name = \"m\"\nservo_period = 0.001\n\n[[axis]]\nletter = \"X\"\n\
        max_velocity = 10\n\n[[axis]]\nletter = \"Y\"\nmax_velocity = -1\n\
        backend = { kind = \"canopen\", bus = \"can0\" }\n\n[spindle]\nmax_rpm = 100\n\n\
        [spindle.backend]\nkind = \"sim\"\nacceleration = 0\n\n[[fault]]\nkind = \"drive\"\n\
        axis = \"Q\"\nat = -1\n";

    #[test]
    fn keys_named_by_validation_messages_are_found() {
        let at = |m: &str| locate(TEXT, m);
        assert_eq!(
            at("axis Y: max_velocity must be a positive number"),
            Some((10, 1))
        );
        assert_eq!(at("axis X: max_velocity = 1e-300 is outside"), Some((6, 1)));
        assert_eq!(at("axis Y: no [canopen.can0] bus").map(|p| p.0), Some(11));
        assert_eq!(
            at("spindle.max_rpm must be a positive number"),
            Some((14, 1))
        );
        assert_eq!(at("spindle simulation acceleration must be"), Some((18, 1)));
        assert_eq!(at("fault Drive: at must be seconds >= 0"), Some((23, 1)));
        assert_eq!(at("servo_period 1 s is longer than 0.1 s"), Some((2, 1)));
        assert_eq!(at("axis Z: max_velocity"), None);
    }

    #[test]
    fn a_second_axis_with_the_same_letter_points_at_its_letter() {
        let text = "[[axis]]\nletter = \"X\"\n[[axis]]\nletter = 'X'\n";
        assert_eq!(locate(text, "axis X is defined twice"), Some((4, 1)));
    }

    #[test]
    fn unknown_keys_point_at_the_key_with_a_hint() {
        let text = "[spindle]\nmax_rpm = 1\n[spindle.backend]\nkind = \"sim\"\nacceleratoin = 5\n";
        let m = "TOML parse error at line 3, column 1\n  |\n3 | [spindle.backend]\n  | ^\n\
                 unknown field `acceleratoin`, expected one of `kind`, `acceleration`\n";
        let (at, out) = unknown_key(text, m);
        assert_eq!(at, Some((5, 1)));
        assert!(
            out.starts_with("unknown key `acceleratoin` — did you mean `acceleration`?"),
            "{out}"
        );
        let m = "TOML parse error at line 3, column 1\n  |\n3 | [spindle.backend]\n  | ^\n\
                 invalid type: string \"fast\", expected f64\n";
        let typed = text.replace("acceleratoin = 5", "acceleration = \"fast\"");
        assert_eq!(
            unknown_key(&typed, m),
            (
                Some((5, 1)),
                "acceleration: invalid type: string \"fast\", expected f64".to_string()
            )
        );
        assert_eq!(
            closest("max_velocty", &["max_velocity", "max_jerk"]),
            Some("max_velocity")
        );
        assert_eq!(closest("colour", &["max_velocity", "max_jerk"]), None);
    }
}
