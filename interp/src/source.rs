//! Streaming block reader: turns program bytes into logical blocks, one at a time.
//!
//! A block is one physical line, or several when a line ends in `~` (continuation). Line ends
//! may be LF or CRLF; the last line needs no line end. The joined block text keeps the raw
//! bytes (the `~` becomes a space, physical lines are joined with `\n`), so a `;` comment ends
//! at the end of its physical line.
//!
//! Klartext readers ([`BlockReader::klartext`]) know the `;` comment: a `~` before a trailing
//! comment (`CYCL DEF 200 BOHREN ~ ;note`) continues the block too, and a `~` at the end of a
//! comment is kept in the text, where it tells the lexer that the comment goes on over the
//! next line (a control wraps long comments that way).
//!
//! Bytes are never decoded up front: columns are computed on demand, counting UTF-8
//! characters when the physical line is valid UTF-8 and bytes (latin-1) otherwise. Only the current block is held in memory; each block remembers the byte offset
//! and line of its first physical line so that a later jump can seek back to it.

use std::io::{self, BufRead, Seek, SeekFrom};

/// Longest block klar reads, in bytes (all its physical lines together, line ends included).
///
/// klar's own limit: NC programs keep blocks short (the longest in the corpus is about 110
/// characters; a CYCL DEF with its parameters on continuation lines is a few hundred), so
/// 4096 leaves ample room while a file without line ends (a stray binary, `/dev/zero`) cannot
/// make the reader grow without bound. A longer block ends the program with an error at its
/// first line.
pub const MAX_BLOCK_BYTES: usize = 4096;

/// The error of a block longer than [`MAX_BLOCK_BYTES`].
fn too_long() -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!(
            "block longer than {MAX_BLOCK_BYTES} characters (klar's limit for one block; \
             a file without line ends?)"
        ),
    )
}

/// Appends one physical line (up to and including `\n`) of `input` to `buf`, reading at most
/// `room` bytes; returns the bytes read, 0 at the end of the input. More than `room` bytes
/// without a line end is a block too long ([`too_long`]).
fn read_line_bounded(input: &mut dyn BufRead, buf: &mut Vec<u8>, room: usize) -> io::Result<usize> {
    let mut read = 0;
    loop {
        let avail = match input.fill_buf() {
            Ok(a) => a,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if avail.is_empty() {
            return Ok(read);
        }
        let (take, done) = match avail.iter().position(|&b| b == b'\n') {
            Some(i) => (i + 1, true),
            None => (avail.len(), false),
        };
        if read + take > room {
            return Err(too_long());
        }
        buf.extend_from_slice(avail.get(..take).unwrap_or(&[]));
        input.consume(take);
        read += take;
        if done {
            return Ok(read);
        }
    }
}

/// A byte source the interpreter can read blocks from and seek in.
pub(crate) trait ProgramInput: BufRead + Seek + Send {}
impl<T: BufRead + Seek + Send> ProgramInput for T {}

/// One physical line inside the joined block text.
#[derive(Debug, Clone, Copy)]
struct Segment {
    /// Start of the line in the block buffer.
    start: usize,
    /// 1-based line number.
    line: u32,
}

/// Where a block starts in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct BlockStart {
    /// Byte offset of the block's first physical line.
    pub offset: u64,
    /// 1-based line of that physical line.
    pub line: u32,
}

/// Reads logical blocks from a program source into a reused buffer.
pub(crate) struct BlockReader {
    input: Box<dyn ProgramInput>,
    buf: Vec<u8>,
    segs: Vec<Segment>,
    next_line: u32,
    next_offset: u64,
    /// Line and column just after the last byte read (for "missing at end of file").
    end_pos: (u32, u32),
    /// Klartext: `;` starts a comment (see the module notes).
    klartext: bool,
    /// A line read ahead (to see whether it continues an SPL block) and not used yet.
    held: Vec<u8>,
    /// True when `held` holds such a line.
    held_ready: bool,
}

impl BlockReader {
    /// Wraps a source positioned at its start.
    pub fn new(input: Box<dyn ProgramInput>) -> Self {
        BlockReader {
            input,
            buf: Vec::with_capacity(256),
            segs: Vec::with_capacity(4),
            next_line: 1,
            next_offset: 0,
            end_pos: (1, 1),
            klartext: false,
            held: Vec::new(),
            held_ready: false,
        }
    }

    /// Wraps a Klartext source positioned at its start: `~` continuations know `;` comments
    /// (see the module notes).
    pub fn klartext(input: Box<dyn ProgramInput>) -> Self {
        BlockReader {
            klartext: true,
            ..BlockReader::new(input)
        }
    }

    /// The text of the current block.
    pub fn text(&self) -> &[u8] {
        &self.buf
    }

    /// Line and column just after the end of the text read so far.
    pub fn end_position(&self) -> (u32, u32) {
        self.end_pos
    }

    /// Reads the next block; `Ok(None)` at end of input.
    pub fn next_block(&mut self) -> io::Result<Option<BlockStart>> {
        self.buf.clear();
        self.segs.clear();
        let start = BlockStart {
            offset: self.next_offset,
            line: self.next_line,
        };
        let mut any = false;
        // the line read continues a comment (the one before ended in a comment and `~`)
        let mut in_comment = false;
        loop {
            if !self.buf.is_empty() {
                self.buf.push(b'\n');
            }
            let seg_start = self.buf.len();
            let n = match self.read_line() {
                Ok(n) => n,
                Err(e) => {
                    // the error is reported at the first line of the block
                    self.end_pos = (start.line, 1);
                    self.buf.clear();
                    self.segs.clear();
                    return Err(e);
                }
            };
            if n == 0 {
                // nothing more: drop the separator pushed for a continuation
                self.buf
                    .truncate(seg_start.saturating_sub(usize::from(any)));
                break;
            }
            any = true;
            self.next_offset += n as u64;
            let line_no = self.next_line;
            self.next_line = self.next_line.saturating_add(1);
            let mut end = self.buf.len();
            let had_newline = self.buf.last() == Some(&b'\n');
            if had_newline {
                end -= 1;
            }
            if end > seg_start && self.buf.get(end - 1) == Some(&b'\r') {
                end -= 1;
            }
            self.buf.truncate(end);
            let body = self.buf.get(seg_start..).unwrap_or(&[]);
            self.end_pos = if had_newline {
                (self.next_line, 1)
            } else {
                (line_no, char_count(body) + 1)
            };
            self.segs.push(Segment {
                start: seg_start,
                line: line_no,
            });
            match continuation(body, self.klartext, in_comment) {
                Some(Tilde::Code(i)) => {
                    in_comment = false;
                    if let Some(b) = self.buf.get_mut(seg_start + i) {
                        *b = b' ';
                    }
                }
                Some(Tilde::Comment) => in_comment = true,
                None if self.klartext && self.spline_goes_on()? => in_comment = false,
                None => break,
            }
        }
        Ok(if any { Some(start) } else { None })
    }

    /// Appends the next physical line (the one read ahead, if any) to the block buffer;
    /// returns its length in bytes, 0 at the end of the input.
    fn read_line(&mut self) -> io::Result<usize> {
        if self.held_ready {
            self.held_ready = false;
            if self.buf.len() + self.held.len() > MAX_BLOCK_BYTES {
                return Err(too_long());
            }
            self.buf.extend_from_slice(&self.held);
            return Ok(self.held.len());
        }
        let room = MAX_BLOCK_BYTES.saturating_sub(self.buf.len());
        read_line_bounded(&mut self.input, &mut self.buf, room)
    }

    /// True when the block read so far is an SPL block and the next line starts with a
    /// spline coefficient (`K3X…`): the manual prints an SPL block that way, its coefficient
    /// lines without block number or `~`. The next line is read ahead and kept.
    fn spline_goes_on(&mut self) -> io::Result<bool> {
        if !is_spline_block(&self.buf) {
            return Ok(false);
        }
        if !self.held_ready {
            self.held.clear();
            if read_line_bounded(&mut self.input, &mut self.held, MAX_BLOCK_BYTES)? == 0 {
                return Ok(false);
            }
            self.held_ready = true;
        }
        Ok(starts_with_coefficient(&self.held))
    }

    /// Line and column (1-based, in characters) of a byte position in the current block.
    pub fn position(&self, pos: usize) -> (u32, u32) {
        let pos = pos.min(self.buf.len());
        if let [only] = self.segs.as_slice()
            && self.buf.get(..pos).is_some_and(<[u8]>::is_ascii)
        {
            // one physical line and an ASCII prefix: the column is the byte offset
            return (only.line, pos as u32 + 1);
        }
        let seg_index = self.segs.iter().rposition(|s| s.start <= pos).unwrap_or(0);
        let Some(seg) = self.segs.get(seg_index) else {
            return (self.next_line, 1);
        };
        let seg_end = self
            .segs
            .get(seg_index + 1)
            .map_or(self.buf.len(), |s| s.start.saturating_sub(1));
        let line_bytes = self.buf.get(seg.start..seg_end).unwrap_or(&[]);
        let prefix = self.buf.get(seg.start..pos).unwrap_or(&[]);
        if prefix.is_ascii() {
            // ASCII counts one character per byte in UTF-8 and latin-1 alike
            return (seg.line, prefix.len() as u32 + 1);
        }
        let col = if std::str::from_utf8(line_bytes).is_ok() {
            char_count(prefix)
        } else {
            prefix.len() as u32
        };
        (seg.line, col + 1)
    }

    /// Where the next block will start (the return point of a subprogram call).
    pub fn next_start(&self) -> BlockStart {
        BlockStart {
            offset: self.next_offset,
            line: self.next_line,
        }
    }

    /// Moves the reader so that the next block read starts at `start` (for jumps).
    pub fn seek(&mut self, start: BlockStart) -> io::Result<()> {
        self.held_ready = false;
        self.input.seek(SeekFrom::Start(start.offset))?;
        self.next_offset = start.offset;
        self.next_line = start.line;
        Ok(())
    }
}

/// A `~` that continues a block on the next line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Tilde {
    /// In the code of the line, at this byte: it becomes a blank.
    Code(usize),
    /// At the end of a Klartext comment: it stays in the text for the lexer.
    Comment,
}

/// Whether a physical line continues on the next one: its last non-blank byte is `~`, or (in
/// Klartext) the last non-blank byte before a trailing `;` comment is. `in_comment`: the whole
/// line is the continuation of a comment.
fn continuation(line: &[u8], klartext: bool, in_comment: bool) -> Option<Tilde> {
    let last = |s: &[u8]| s.iter().rposition(|b| !b.is_ascii_whitespace());
    let end = last(line)?;
    let code_end = match (klartext, in_comment) {
        (false, _) => None,
        (true, true) => Some(0),
        (true, false) => comment_start(line),
    };
    match code_end {
        Some(c) => match last(line.get(..c).unwrap_or(&[])) {
            Some(i) if line.get(i) == Some(&b'~') => Some(Tilde::Code(i)),
            _ if line.get(end) == Some(&b'~') => Some(Tilde::Comment),
            _ => None,
        },
        None if line.get(end) == Some(&b'~') => Some(Tilde::Code(end)),
        None => None,
    }
}

/// True for a Klartext block whose keyword is `SPL` (`[/][N]nr[/] SPL …`).
fn is_spline_block(text: &[u8]) -> bool {
    let mut i = 0;
    let blanks = |i: &mut usize| {
        while matches!(text.get(*i), Some(b' ' | b'\t')) {
            *i += 1;
        }
    };
    blanks(&mut i);
    if text.get(i) == Some(&b'/') {
        i += 1;
        blanks(&mut i);
    }
    if text.get(i).is_some_and(|b| b.eq_ignore_ascii_case(&b'N'))
        && text.get(i + 1).is_some_and(u8::is_ascii_digit)
    {
        i += 1;
    }
    while text.get(i).is_some_and(u8::is_ascii_digit) {
        i += 1;
    }
    blanks(&mut i);
    if text.get(i) == Some(&b'/') {
        i += 1;
        blanks(&mut i);
    }
    text.get(i..i + 3)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"SPL"))
        && !text
            .get(i + 3)
            .is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_')
}

/// True for a line that starts (after blanks) with a spline coefficient word `K3X`, `K2Y`,
/// `K1A`, … .
fn starts_with_coefficient(line: &[u8]) -> bool {
    let i = line
        .iter()
        .position(|b| !matches!(b, b' ' | b'\t'))
        .unwrap_or(line.len());
    matches!(
        line.get(i..i + 3),
        Some([k, b'1'..=b'3', axis])
            if k.eq_ignore_ascii_case(&b'K') && b"XYZABCUVW".contains(&axis.to_ascii_uppercase())
    )
}

/// Where the `;` comment of a Klartext line starts (a `;` inside `"…"` is text).
fn comment_start(line: &[u8]) -> Option<usize> {
    let mut quoted = false;
    for (i, &b) in line.iter().enumerate() {
        match b {
            b'"' => quoted = !quoted,
            b';' if !quoted => return Some(i),
            _ => {}
        }
    }
    None
}

/// Characters in a UTF-8 byte slice, counting latin-1 bytes as one each when invalid.
fn char_count(bytes: &[u8]) -> u32 {
    if std::str::from_utf8(bytes).is_ok() {
        bytes.iter().filter(|&&b| (b & 0xC0) != 0x80).count() as u32
    } else {
        bytes.len() as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn reader(text: &[u8]) -> BlockReader {
        BlockReader::new(Box::new(Cursor::new(text.to_vec())))
    }

    #[test]
    fn joins_continuation_lines_and_tracks_lines() {
        let mut r = reader(b"1 Q1 = 2 + ~\r\n   3\r\n2 L X+1");
        let b = r.next_block().unwrap().unwrap();
        assert_eq!(b, BlockStart { offset: 0, line: 1 });
        assert_eq!(r.text(), b"1 Q1 = 2 +  \n   3");
        // the `3` sits on line 2, column 4
        let pos = r.text().iter().position(|&c| c == b'3').unwrap();
        assert_eq!(r.position(pos), (2, 4));
        let b = r.next_block().unwrap().unwrap();
        assert_eq!(
            b,
            BlockStart {
                offset: 20,
                line: 3
            }
        );
        assert_eq!(r.text(), b"2 L X+1");
        assert_eq!(r.end_position(), (3, 8));
        assert!(r.next_block().unwrap().is_none());
    }

    #[test]
    fn klartext_comments_and_tildes() {
        let mut r = BlockReader::klartext(Box::new(Cursor::new(
            b"1 CYCL DEF 200 X ~ ;note\n Q200=2 ;A ~\n Q201=3\n2 L ; a ~ b\n3 QS1 = \"a;~\" ~\n + \"b\"\n".to_vec(),
        )));
        r.next_block().unwrap();
        // the `~` before the comment continues the block and becomes a blank; the one at
        // the end of a comment stays for the lexer
        assert_eq!(r.text(), b"1 CYCL DEF 200 X   ;note\n Q200=2 ;A ~\n Q201=3");
        r.next_block().unwrap();
        assert_eq!(r.text(), b"2 L ; a ~ b");
        r.next_block().unwrap();
        assert_eq!(r.text(), b"3 QS1 = \"a;~\"  \n + \"b\"");
        // other dialects know no `;` comment: only a final `~` continues
        let mut r = reader(b"N10 G01 ~ ;x\nN20\n");
        r.next_block().unwrap();
        assert_eq!(r.text(), b"N10 G01 ~ ;x");
    }

    #[test]
    fn spline_coefficient_lines_join_the_spl_block() {
        let text = b"7 SPL X+1 Y+2\n K3X+0 K2X+0 K1X+1\nK3Y+0 K2Y+0 K1Y+2 F100\n8 L X+0\nK3X+1\n";
        let mut r = BlockReader::klartext(Box::new(Cursor::new(text.to_vec())));
        let b = r.next_block().unwrap().unwrap();
        assert_eq!(b, BlockStart { offset: 0, line: 1 });
        assert_eq!(
            r.text(),
            b"7 SPL X+1 Y+2\n K3X+0 K2X+0 K1X+1\nK3Y+0 K2Y+0 K1Y+2 F100"
        );
        let k = r.text().iter().rposition(|&c| c == b'K').unwrap();
        assert_eq!(r.position(k), (3, 13));
        // the line read ahead starts the next block, at its own offset and line
        assert_eq!(
            r.next_start(),
            BlockStart {
                offset: 56,
                line: 4
            }
        );
        let b = r.next_block().unwrap().unwrap();
        assert_eq!(
            b,
            BlockStart {
                offset: 56,
                line: 4
            }
        );
        assert_eq!(r.text(), b"8 L X+0");
        // after any other block a K line stays a block of its own
        r.next_block().unwrap();
        assert_eq!(r.text(), b"K3X+1");
        assert!(r.next_block().unwrap().is_none());
        // a seek drops the line read ahead
        let mut r = BlockReader::klartext(Box::new(Cursor::new(b"SPL X+1\nL X+2\n".to_vec())));
        r.next_block().unwrap();
        r.seek(BlockStart { offset: 0, line: 1 }).unwrap();
        r.next_block().unwrap();
        assert_eq!(r.text(), b"SPL X+1");
        r.next_block().unwrap();
        assert_eq!(r.text(), b"L X+2");
    }

    #[test]
    fn columns_count_characters_or_latin1_bytes() {
        // "ä" in UTF-8 is two bytes, one character
        let mut r = reader("; ä X\n".as_bytes());
        r.next_block().unwrap();
        let x = r.text().iter().position(|&c| c == b'X').unwrap();
        assert_eq!(r.position(x), (1, 5));
        // 0xE4 alone is latin-1 "ä": one byte, one character
        let mut r = reader(b"; \xE4 X\n");
        r.next_block().unwrap();
        let x = r.text().iter().position(|&c| c == b'X').unwrap();
        assert_eq!(r.position(x), (1, 5));
    }

    #[test]
    fn a_block_longer_than_the_limit_is_refused_without_reading_it_all() {
        // a line of exactly the limit (line end included) is read
        let mut line = vec![b'X'; MAX_BLOCK_BYTES - 1];
        line.push(b'\n');
        line.extend_from_slice(b"NEXT\n");
        let mut r = reader(&line);
        r.next_block().unwrap();
        assert_eq!(r.text().len(), MAX_BLOCK_BYTES - 1);
        r.next_block().unwrap();
        assert_eq!(r.text(), b"NEXT");
        // one byte more on line 2 is refused there; the reader stops right after the limit
        let mut text = b"A\n".to_vec();
        text.extend(std::iter::repeat_n(b'Y', 10 * MAX_BLOCK_BYTES));
        let mut r = BlockReader::new(Box::new(io::BufReader::with_capacity(
            64,
            Cursor::new(text),
        )));
        r.next_block().unwrap();
        let e = r.next_block().unwrap_err();
        assert!(e.to_string().contains("longer than 4096 characters"), "{e}");
        assert_eq!(r.end_position(), (2, 1));
        assert!(r.text().is_empty());
        // continuation lines count together
        let mut text = Vec::new();
        for _ in 0..MAX_BLOCK_BYTES / 4 {
            text.extend_from_slice(b"Q1=1 ~\n");
        }
        text.extend_from_slice(b"Q1=1\n");
        let mut r = reader(&text);
        assert!(r.next_block().is_err());
    }

    #[test]
    fn seek_rereads_a_block() {
        let mut r = reader(b"A\nB\nC\n");
        r.next_block().unwrap();
        let b = r.next_block().unwrap().unwrap();
        r.next_block().unwrap();
        r.seek(b).unwrap();
        let again = r.next_block().unwrap().unwrap();
        assert_eq!(again, b);
        assert_eq!(r.text(), b"B");
    }
}
