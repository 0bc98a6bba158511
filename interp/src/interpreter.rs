//! The streaming interpreter and the whole-program checks built on it.

use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{BufRead, BufReader, Cursor};
use std::path::{Path, PathBuf};

use crate::diag::{Diagnostic, ProgramError};
use crate::dialect::{Dialect, DialectRun, detect_dialect, runner};
use crate::klartext::parser::{Block, LabelRef, Parser, Stmt, is_begin_block};
use crate::op::{Op, Pose, SourceLoc};
use crate::source::{BlockReader, BlockStart, ProgramInput};
use crate::tnc::cycle_table::DatumTable;
use crate::tnc::exec::{Blank, Flow, LabelKey, Machine};
use crate::tnc::tools::ToolTable;

#[path = "interpreter_check.rs"]
mod check;
#[path = "interpreter_flow.rs"]
mod flow;

pub use check::{CheckReport, check, check_report, syntax_check};

/// How much of each block is processed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Execute and stop at the first error (the iterator).
    Run,
    /// Execute, report every error and go on.
    Check,
    /// Parse only.
    Syntax,
}

/// Where the program is in its structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// No BEGIN PGM yet.
    BeforeBegin,
    /// Between BEGIN PGM and the end.
    Running,
    /// M2/M30 reached: the rest is only checked for syntax (subprograms live there).
    Stopped,
    /// END PGM read.
    Ended,
    /// Nothing more to read.
    Done,
}

/// Deepest nesting of subprogram calls (CALL LBL), as on the TNC.
pub const MAX_SUBPROGRAM_DEPTH: usize = 8;

/// Deepest nesting of program calls (CALL PGM), as on the TNC.
pub const MAX_PROGRAM_DEPTH: usize = 4;

/// Most jumps a `check` run follows before it reports an endless loop (a check skips
/// blocks with errors, so a loop counter that fails to change would never end).
pub const CHECK_JUMP_LIMIT: u64 = 100_000;

/// Most jumps a run follows without producing any op (no motion, no machine function) before
/// it stops with an "endless loop" error: a loop that neither moves nor switches anything can
/// never end differently, and a control must not hang silently on it. The same number as
/// [`CHECK_JUMP_LIMIT`] (and the TNC ISO runner's idle limit): a program the check accepts
/// never reaches it, and the op pass of the test run gives up on an idle loop as soon as the
/// check does.
pub const RUN_IDLE_JUMP_LIMIT: u64 = 100_000;

/// Most diagnostics one `check` run reports before it gives up (an error inside a loop
/// would otherwise repeat with every pass).
pub const CHECK_DIAGNOSTIC_LIMIT: usize = 200;

/// One program file being executed: its reader, labels and call state.
struct Unit {
    /// The file.
    path: PathBuf,
    /// Index in the interpreter's file table.
    file_id: u16,
    /// Block reader.
    reader: BlockReader,
    /// Where the program is in its structure.
    phase: Phase,
    /// Labels seen so far and where their blocks start.
    labels: HashMap<LabelKey, BlockStart>,
    /// Every block before this point has been read once (labels recorded).
    seen_to: BlockStart,
    /// Return points of the active subprogram calls.
    calls: Vec<BlockStart>,
    /// Repeats left per section-repeat block (keyed by the block's byte offset).
    repeats: HashMap<u64, u32>,
    /// Blocks before BEGIN PGM that were passed over: where the first starts (line,
    /// column) and the last line they took.
    ignored: Option<(u32, u32, u32)>,
    /// The program name written in BEGIN PGM.
    begin_name: Vec<u8>,
}

impl Unit {
    fn new(path: PathBuf, file_id: u16, input: Box<dyn ProgramInput>) -> Self {
        Unit {
            path,
            file_id,
            reader: BlockReader::klartext(input),
            phase: Phase::BeforeBegin,
            labels: HashMap::new(),
            seen_to: BlockStart { offset: 0, line: 1 },
            calls: Vec::new(),
            repeats: HashMap::new(),
            ignored: None,
            begin_name: Vec::new(),
        }
    }
}

/// Streaming Klartext interpreter: an iterator of ops, one block at a time.
///
/// Yields `Ok(op)` for every op in program order; after a diagnostic, the end of the program
/// (END PGM, M2, M30) or the end of the text it yields `None`. The last contour element is
/// handed out one block late, because an RND or CHF in the next block may still shorten it.
///
/// Jumps and calls (FN 9–12, CALL LBL, REP, CALL PGM) seek in the file: labels are recorded
/// as blocks are read, and a jump to a label not seen yet reads ahead to find it, so the
/// program is never held in memory.
pub struct Interpreter {
    files: Vec<PathBuf>,
    units: Vec<Unit>,
    parser: Parser,
    machine: Machine,
    queue: VecDeque<Op>,
    blocks: u64,
    block_skip: bool,
    finished: bool,
    done: bool,
    /// Where the current block starts in its file.
    current: BlockStart,
    /// A diagnostic to hand out after the ops that precede it.
    pending_error: Option<Diagnostic>,
    /// Jumps followed so far (bounded in check runs).
    jumps: u64,
    /// Jumps since the last op was handed out (run mode).
    idle_jumps: u64,
    /// The runner of a TNC ISO or lathe DIN program, which this interpreter delegates to.
    other: Option<Box<dyn DialectRun>>,
    /// Check runs: what cannot be decided before the run (see [`check_report`]).
    undecided: Vec<Diagnostic>,
    /// Check runs: files the program reads that are not there (see [`check_report`]).
    missing: Vec<Diagnostic>,
    /// Check runs: from this point on the program's values depend on the machine (a position
    /// the operator set during a program stop, a called program or a table that is not
    /// there): what it says in words.
    depends_on: Option<String>,
    /// Forms accepted with leniency (see [`Interpreter::warnings`]).
    warnings: Vec<Diagnostic>,
}

impl std::fmt::Debug for Interpreter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Interpreter")
            .field("files", &self.files)
            .field("blocks", &self.blocks)
            .finish_non_exhaustive()
    }
}

pub(crate) fn whole_file_error(file: &Path, error: &ProgramError) -> Diagnostic {
    Diagnostic::new(file.to_path_buf(), 1, 1, None, error)
}

/// Opens a program file and recognises its dialect.
pub(crate) fn open_any(path: &Path) -> Result<(Dialect, Box<dyn ProgramInput>), Diagnostic> {
    // a FIFO or a device would block or never end: refused before it is opened
    if let Some(kind) = crate::files::not_a_file(path) {
        return Err(whole_file_error(path, &ProgramError::NotAFile(kind)));
    }
    let file =
        File::open(path).map_err(|e| whole_file_error(path, &ProgramError::Io(e.to_string())))?;
    let mut reader = BufReader::with_capacity(64 * 1024, file);
    let head = reader
        .fill_buf()
        .map_err(|e| whole_file_error(path, &ProgramError::Io(e.to_string())))?;
    let head = &head[..head.len().min(4096)];
    match detect_dialect(path, head) {
        Some(d) => Ok((d, Box::new(reader))),
        None => Err(whole_file_error(path, &ProgramError::UnknownDialect)),
    }
}

impl Interpreter {
    /// Opens a program file; `start` is where the machine stands before the first block.
    ///
    /// Fails when the file cannot be read or is not in a dialect this version runs.
    pub fn open(path: &Path, start: Pose) -> Result<Self, Diagnostic> {
        let (dialect, input) = open_any(path)?;
        tracing::debug!(file = %path.display(), dialect = dialect.name(), "opened program");
        if dialect == Dialect::Klartext {
            let mut it = Self::with_input(path.to_path_buf(), input, start);
            it.machine.set_program_file(path);
            return Ok(it);
        }
        let mut it = Self::with_input(path.to_path_buf(), Box::new(Cursor::new(Vec::new())), start);
        it.other = runner(dialect, path.to_path_buf(), input, start);
        Ok(it)
    }

    /// A dry run (the test run): files are read but none is written (FN 16 output and FN 27
    /// table writes are kept in memory).
    pub fn set_dry_run(&mut self, on: bool) {
        self.target().set_dry_run(on);
    }

    /// Interprets a program held in memory (tests, benches); `name` is used in diagnostics and
    /// as the folder CALL PGM paths are relative to. The dialect is recognised from `name` and
    /// the text as for files (TNC ISO for `.i`, lathe DIN for `.nc`); Klartext when neither
    /// tells.
    pub fn from_source(name: &str, text: &str, start: Pose) -> Self {
        let input = Box::new(Cursor::new(text.as_bytes().to_vec()));
        let dialect = detect_dialect(Path::new(name), text.as_bytes()).unwrap_or(Dialect::Klartext);
        if dialect == Dialect::Klartext {
            let mut it = Self::with_input(PathBuf::from(name), input, start);
            it.machine.set_program_file(Path::new(name));
            return it;
        }
        let mut it = Self::with_input(
            PathBuf::from(name),
            Box::new(Cursor::new(Vec::new())),
            start,
        );
        it.other = runner(dialect, PathBuf::from(name), input, start);
        it
    }

    fn with_input(file: PathBuf, input: Box<dyn ProgramInput>, start: Pose) -> Self {
        Interpreter {
            files: vec![file.clone()],
            units: vec![Unit::new(file, 0, input)],
            parser: Parser::default(),
            machine: Machine::new(start),
            queue: VecDeque::with_capacity(8),
            blocks: 0,
            block_skip: true,
            finished: false,
            done: false,
            current: BlockStart { offset: 0, line: 1 },
            pending_error: None,
            jumps: 0,
            idle_jumps: 0,
            other: None,
            undecided: Vec::new(),
            missing: Vec::new(),
            depends_on: None,
            warnings: Vec::new(),
        }
    }

    /// The Klartext machine that executes the program: the TNC ISO runner's own (ISO blocks
    /// run as the Klartext statements with the same meaning), else this interpreter's. Every
    /// setter that tells the interpreter about the machine goes through here, so that it
    /// reaches Klartext and TNC ISO programs alike.
    fn target(&mut self) -> &mut Machine {
        match self.other.as_mut().and_then(|o| o.klartext_machine()) {
            Some(m) => m,
            None => &mut self.machine,
        }
    }

    /// Read access to the machine of [`Self::target`].
    fn target_ref(&self) -> &Machine {
        match self.other.as_ref().and_then(|o| o.klartext_machine_ref()) {
            Some(m) => m,
            None => &self.machine,
        }
    }

    /// Uses `tools` for TOOL CALL (Klartext) and `T…` (TNC ISO): length and radius come from
    /// the table (plus the table's and the call's DL/DR), and calling a tool missing from a
    /// non-empty table is an error.
    ///
    /// Lathe DIN programs take none of the machine settings of the `with_*`/`set_*` methods
    /// except block skip: their tools are named in the TURRET section and their ops are
    /// tool-tip positions (a lathe tool is described by setting dimensions in X and Z and a
    /// cutting-edge radius, not by the length and radius of a milling tool table); C is the
    /// main spindle, not a table axis for PLANE; they have no M functions of the machine
    /// builder, datum tables or tilted working plane of the mill.
    pub fn with_tools(mut self, tools: ToolTable) -> Self {
        self.target().set_tools(tools);
        self
    }

    /// Tells the interpreter the machine's axes: PLANE and cycle 19 need a tilt axis (A or
    /// B) and a table axis C, and compute their angles for them (an interpreter never told
    /// assumes an A/C table).
    pub fn with_rotary_axes(mut self, axes: &[crate::op::AxisLetter]) -> Self {
        self.target().set_rotary_axes(axes);
        self
    }

    /// Tells the interpreter the geometry of a table-table machine: the tilt axis (`A` or
    /// `B`), a point on the tilt axis and a point on the table axis C (machine coordinates in
    /// mm with every axis at zero). PLANE … TURN then positions only the rotary axes: the
    /// machine's linear axes stand still and the tool tip ends on the point of the workpiece
    /// that the table has carried under it. Without it (or with another letter) TURN holds
    /// the tool tip on the workpiece like MOVE, since the tip's new place depends on the
    /// pivots. M116 measures the tool point's distance from these axes (a machine named
    /// without them refuses M116 on blocks that turn a table axis).
    pub fn with_table_geometry(
        mut self,
        tilt: crate::op::AxisLetter,
        tilt_pivot: [f64; 3],
        table_pivot: [f64; 3],
    ) -> Self {
        self.target()
            .set_table_geometry(tilt, tilt_pivot, table_pivot);
        self
    }

    /// Tells the interpreter the machine's own M functions (Klartext and TNC ISO programs):
    /// a listed number is passed on as [`crate::op::OpKind::MachineFunction`] at block start
    /// or end as defined, instead of being refused as not supported. Entries with a number
    /// klar defines itself ([`crate::op::BUILT_IN_M_NUMBERS`]) are ignored.
    pub fn with_machine_functions(mut self, defs: &[crate::op::MachineFunctionDef]) -> Self {
        self.target().set_machine_functions(defs);
        self
    }

    /// Working-plane ops (`on`): in a tilted working plane (PLANE, cycle 19) the ops stay in
    /// the tilted system and [`crate::OpKind::WorkingPlane`] marks each change of the plane,
    /// so that radius compensation (RL/RR, APPR/DEP) can run in the tilted plane before the
    /// ops are turned into the workpiece system (klar-motion's compensation stage does both).
    /// Off (the default), ops leave in workpiece coordinates and RL/RR, APPR and DEP are
    /// refused while a plane is tilted. Klartext and TNC ISO programs (G80, G41/G42, G26/G27).
    pub fn set_working_plane_ops(&mut self, on: bool) {
        self.target().set_working_plane_ops(on);
    }

    /// Uses `table` for datum shifts from a datum table (`CYCL DEF 7.1 #n`, ISO `G53 P01 n`).
    pub fn with_datum_table(mut self, table: DatumTable) -> Self {
        self.target().set_datum_table(table);
        self
    }

    /// Uses `table` for presets activated by cycle 247 (`Q339` = row number).
    pub fn with_preset_table(mut self, table: DatumTable) -> Self {
        self.target().set_preset_table(table);
        self
    }

    /// Makes row `nr` of the preset table (see [`Self::with_preset_table`]) active from the
    /// program's start, as the operator's active preset on the machine; without such a row
    /// nothing changes (a machine file naming a missing row is refused when it is loaded).
    pub fn with_active_preset(mut self, nr: i64) -> Self {
        self.target().activate_preset(nr);
        self
    }

    /// Gives the interpreter a touch probe: `TCH PROBE` cycles ask `probe` where the stylus
    /// touches and use `data` (ball radius, clearance, probing distance, feeds). Without one
    /// they are refused. Klartext and TNC ISO programs.
    pub fn with_probe(
        mut self,
        data: crate::probe::ProbeData,
        probe: Box<dyn crate::probe::Probe>,
    ) -> Self {
        self.target().set_probe(data, probe);
        self
    }

    /// Measured probing: `TCH PROBE` cycles take each touch point from the machine (the
    /// drives' touch-probe latches) instead of asking a probe model. At each probing move the
    /// interpreter hands out the ops before it and then yields `None` with
    /// [`Interpreter::probe_request`] set: the machine runs the probing move itself and
    /// [`Interpreter::answer_probe`] lets the program go on from where the axes stopped.
    /// `data` as for [`Interpreter::with_probe`]. Klartext programs (TNC ISO `G4nn` are
    /// refused on such a machine).
    pub fn with_measured_probing(mut self, data: crate::probe::ProbeData) -> Self {
        self.target().set_measured_probing(data);
        self
    }

    /// The probing move the interpreter waits for the machine to measure, if any.
    pub fn probe_request(&self) -> Option<crate::probe::ProbeRequest> {
        self.target_ref().probe_request()
    }

    /// The machine's answer to [`Interpreter::probe_request`]: the program goes on.
    pub fn answer_probe(&mut self, answer: crate::probe::ProbeAnswer) {
        self.target().answer_probe(answer);
    }

    /// The value of Q parameter `n` now (0 when never set): the results of touch-probe cycles
    /// (Q150 and up) for whoever runs the program.
    pub fn q(&self, n: u32) -> f64 {
        self.target_ref()
            .params
            .value(crate::tnc::expr::Value::Param {
                param: crate::tnc::expr::ParamRef {
                    kind: crate::tnc::expr::ParamKind::Q,
                    index: n,
                },
                negate: false,
            })
    }

    /// The preset table as the program has left it so far (touch-probe cycles write it), and
    /// the row active now.
    pub fn presets(&self) -> (Option<&DatumTable>, Option<i64>) {
        let m = self.target_ref();
        (m.cyc.presets.as_ref(), m.cyc.active_preset)
    }

    /// Tells the interpreter the travel `[min, max]` (mm, machine coordinates) of the linear
    /// machine axis `axis` (X, Y or Z; other letters are ignored): `M140 MB MAX` retracts along
    /// the tool axis until the first linear axis reaches its travel limit.
    pub fn with_travel(mut self, axis: crate::op::AxisLetter, travel: [f64; 2]) -> Self {
        if let Some(slot) = self.target().travel.get_mut(axis.index()) {
            *slot = Some(travel);
        }
        self
    }

    /// Number of blocks executed so far (empty and comment lines not counted).
    pub fn blocks_executed(&self) -> u64 {
        match &self.other {
            Some(o) => o.blocks_executed(),
            None => self.blocks,
        }
    }

    /// Switches block skip: when on (the default) blocks marked `/` are not executed.
    pub fn set_block_skip(&mut self, on: bool) {
        self.block_skip = on;
        if let Some(o) = &mut self.other {
            o.set_block_skip(on);
        }
    }

    /// The blank recorded from BLK FORM (TNC ISO: G30/G31), if any.
    pub fn blank(&self) -> Option<Blank> {
        self.target_ref().blank
    }

    /// Byte offset and line where the block read last starts (in the file running now).
    pub fn block_offset(&self) -> (u64, u32) {
        (self.current.offset, self.current.line)
    }

    /// The last programmed position (mm, degrees).
    pub fn position(&self) -> Pose {
        match &self.other {
            Some(o) => o.last_position(),
            None => self.machine.pos,
        }
    }

    /// Warnings so far: forms that are accepted but not as HEIDENHAIN writes them, each
    /// located as `file:line:col: message` like an error. Lines before `BEGIN PGM` are passed
    /// over (one warning names them when BEGIN PGM comes), and an `END PGM` whose program name
    /// differs from the one of `BEGIN PGM` is warned about. Each warning is kept once, at most
    /// [`CHECK_DIAGNOSTIC_LIMIT`]; TNC ISO and lathe DIN programs have none.
    pub fn warnings(&self) -> &[Diagnostic] {
        &self.warnings
    }

    /// Records a warning (once; at most [`CHECK_DIAGNOSTIC_LIMIT`]).
    fn warn(&mut self, d: Diagnostic) {
        if self.warnings.len() < CHECK_DIAGNOSTIC_LIMIT && !self.warnings.contains(&d) {
            self.warnings.push(d);
        }
    }

    /// Passes over the current block, which stands before BEGIN PGM.
    fn ignore_before_begin(&mut self) {
        let Some(u) = self.units.last_mut() else {
            return;
        };
        let text = u.reader.text();
        let first = text
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(0);
        let (line, col) = u.reader.position(first);
        let (last, _) = u.reader.position(text.len());
        match &mut u.ignored {
            Some((_, _, l)) => *l = last,
            None => u.ignored = Some((line, col, last)),
        }
    }

    /// BEGIN PGM read: the warning about the lines passed over before it, and the name.
    fn note_begin(&mut self) {
        let Some(u) = self.units.last_mut() else {
            return;
        };
        let (s, e) = self.parser.program_name;
        u.begin_name = u.reader.text().get(s..e).unwrap_or(&[]).to_vec();
        if let Some((line, col, last)) = u.ignored.take() {
            let message = if last > line {
                format!("lines {line} to {last} before BEGIN PGM ignored")
            } else {
                format!("line {line} before BEGIN PGM ignored")
            };
            let d = Diagnostic::with_message(u.path.clone(), line, col, None, message);
            self.warn(d);
        }
    }

    /// No BEGIN PGM before END PGM or the end of the text: the error stands where the
    /// program should have begun (the first line passed over), else at `fallback`.
    fn missing_begin(&mut self, fallback: Diagnostic) -> Diagnostic {
        match self.units.last_mut().and_then(|u| u.ignored.take()) {
            Some((line, col, _)) => Diagnostic {
                line,
                col,
                block: None,
                message: ProgramError::MissingBegin.to_string(),
                ..fallback
            },
            None => fallback,
        }
    }

    /// END PGM read: a warning when it names another program than BEGIN PGM.
    fn check_end_name(&mut self, block: &Block) {
        let Some(u) = self.units.last() else {
            return;
        };
        let (s, e) = self.parser.program_name;
        let name = u.reader.text().get(s..e).unwrap_or(&[]);
        if name == u.begin_name.as_slice() {
            return;
        }
        let begin = String::from_utf8_lossy(&u.begin_name);
        let message = if name.is_empty() {
            format!("END PGM names no program (BEGIN PGM {begin})")
        } else {
            format!(
                "END PGM {} does not match BEGIN PGM {begin}",
                String::from_utf8_lossy(name)
            )
        };
        let at = if name.is_empty() { block.start } else { s };
        let (line, col) = u.reader.position(at);
        let d = Diagnostic::with_message(u.path.clone(), line, col, block.number, message);
        self.warn(d);
    }

    /// The program files in use: index = [`SourceLoc::file`] (0 = the main program).
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    fn unit(&self) -> Option<&Unit> {
        self.units.last()
    }

    fn diag_at(&self, pos: usize, block: Option<u64>, error: &ProgramError) -> Diagnostic {
        match self.unit() {
            Some(u) => {
                let (line, col) = u.reader.position(pos);
                Diagnostic::new(u.path.clone(), line, col, block, error)
            }
            None => Diagnostic::new(PathBuf::new(), 1, 1, block, error),
        }
    }

    fn diag_end(&self, error: &ProgramError) -> Diagnostic {
        match self.unit() {
            Some(u) => {
                let (line, col) = u.reader.end_position();
                Diagnostic::new(u.path.clone(), line, col, None, error)
            }
            None => Diagnostic::new(PathBuf::new(), 1, 1, None, error),
        }
    }

    /// Reads and processes one block. Ops go to the queue.
    fn step(&mut self, mode: Mode) -> Result<(), Diagnostic> {
        let Some(u) = self.units.last_mut() else {
            self.done = true;
            return Ok(());
        };
        match u.reader.next_block() {
            Ok(Some(s)) => self.current = s,
            Ok(None) => {
                let was = u.phase;
                u.phase = Phase::Done;
                let error = match was {
                    Phase::Ended => None,
                    Phase::BeforeBegin => Some(ProgramError::MissingBegin),
                    _ => Some(ProgramError::MissingEnd),
                };
                let mut d = error.map(|e| self.diag_end(&e));
                if was == Phase::BeforeBegin {
                    d = d.map(|d| self.missing_begin(d));
                }
                if self.units.len() > 1 && mode != Mode::Syntax && d.is_none() {
                    self.units.pop();
                    self.machine.params.leave_program();
                } else {
                    self.done = true;
                }
                return d.map_or(Ok(()), Err);
            }
            Err(e) => {
                u.phase = Phase::Done;
                self.done = true;
                return Err(self.diag_end(&ProgramError::Io(e.to_string())));
            }
        };
        self.note_seen();
        let Some(u) = self.units.last_mut() else {
            return Ok(());
        };
        let block = match self.parser.parse(u.reader.text()) {
            Ok(b) => b,
            Err(pe) => {
                if u.phase == Phase::BeforeBegin {
                    if !is_begin_block(u.reader.text()) {
                        // text before the program (a CAM header, a `%` line) is passed over
                        self.ignore_before_begin();
                        return Ok(());
                    }
                    u.phase = Phase::Running;
                }
                return Err(self.diag_at(pe.pos, pe.number, &pe.error));
            }
        };
        if matches!(block.stmt, Stmt::Empty) {
            return Ok(());
        }
        if let Stmt::Label(r) = block.stmt
            && u.phase != Phase::BeforeBegin
        {
            let key = LabelKey::from_ref(r, u.reader.text());
            let start = self.current;
            self.note_label(Some(key), start);
        }
        let Some(u) = self.units.last_mut() else {
            return Ok(());
        };
        if matches!(block.stmt, Stmt::EndPgm) && matches!(u.phase, Phase::Running | Phase::Stopped)
        {
            self.check_end_name(&block);
        }
        let Some(u) = self.units.last_mut() else {
            return Ok(());
        };
        match (u.phase, &block.stmt) {
            (Phase::BeforeBegin, Stmt::BeginPgm { inch }) => {
                if self.units.len() == 1 {
                    self.machine.set_inch(*inch);
                }
                if let Some(u) = self.units.last_mut() {
                    u.phase = Phase::Running;
                }
                self.note_begin();
                self.blocks += 1;
                return Ok(());
            }
            (Phase::BeforeBegin, Stmt::EndPgm) => {
                // END PGM without BEGIN PGM: no program at all
                u.phase = Phase::Running;
                let d = self.diag_at(block.start, block.number, &ProgramError::MissingBegin);
                return Err(self.missing_begin(d));
            }
            (Phase::BeforeBegin, _) => {
                self.ignore_before_begin();
                return Ok(());
            }
            (Phase::Ended | Phase::Done, _) => {
                return Err(self.diag_at(block.start, block.number, &ProgramError::AfterEnd));
            }
            (_, Stmt::BeginPgm { .. }) => {
                return Err(self.diag_at(
                    block.start,
                    block.number,
                    &ProgramError::Unexpected("second BEGIN PGM".into()),
                ));
            }
            (Phase::Stopped, Stmt::EndPgm) => {
                u.phase = Phase::Ended;
                return Ok(());
            }
            (Phase::Stopped, _) => return Ok(()),
            (Phase::Running, _) => {}
        }
        if mode == Mode::Syntax {
            if matches!(block.stmt, Stmt::EndPgm) {
                u.phase = Phase::Ended;
            }
            return Ok(());
        }
        if block.skip && self.block_skip {
            return Ok(());
        }
        // LBL 0 closes the running subprogram
        if matches!(block.stmt, Stmt::Label(LabelRef::Num(0)))
            && let Some(ret) = u.calls.pop()
        {
            self.blocks += 1;
            return u.reader.seek(ret).map_err(|e| {
                self.diag_at(block.start, block.number, &ProgramError::Io(e.to_string()))
            });
        }
        // END PGM of a called program returns to the caller
        let called = self.units.len() > 1;
        let Some(u) = self.units.last_mut() else {
            return Ok(());
        };
        if matches!(block.stmt, Stmt::EndPgm) && called {
            self.blocks += 1;
            self.units.pop();
            self.machine.params.leave_program();
            return Ok(());
        }
        let (line, col) = u.reader.position(block.start);
        let loc = SourceLoc {
            file: u.file_id,
            line,
            col,
            block: block.number,
        };
        self.blocks += 1;
        let result = self.machine.exec(
            &block.stmt,
            &self.parser,
            u.reader.text(),
            loc,
            &mut self.queue,
        );
        match result {
            Ok(Flow::Continue) => Ok(()),
            Ok(Flow::End) => {
                let ended = matches!(block.stmt, Stmt::EndPgm);
                for u in &mut self.units {
                    u.phase = if ended { Phase::Ended } else { Phase::Stopped };
                }
                // M2/M30 in a called program end the whole run: drop the callers
                self.units.truncate(1);
                self.machine.release();
                if mode == Mode::Run {
                    self.finished = true;
                }
                Ok(())
            }
            Ok(flow) => {
                // locate now: reading ahead for a label replaces the block text
                let (line, col) = u.reader.position(block.start);
                let file = u.path.clone();
                match self.follow(flow, mode) {
                    // a check of this file goes on past a called program that is not there;
                    // the run stops at the call
                    Err(e @ ProgramError::CallPgm(_)) if mode == Mode::Check => {
                        let d = Diagnostic::new(file, line, col, block.number, &e);
                        self.missing.push(d);
                        self.depends_on
                            .get_or_insert_with(|| format!("the program called at line {line}"));
                        Ok(())
                    }
                    r => r.map_err(|e| Diagnostic::new(file, line, col, block.number, &e)),
                }
            }
            Err((pos, error)) => {
                let p = pos.map_or(block.start, |p| p as usize);
                let d = self.diag_at(p, block.number, &error);
                if mode == Mode::Check && matches!(error, ProgramError::MissingFile(_)) {
                    // a table or format file that lives on the machine, not beside the program
                    let line = d.line;
                    self.missing.push(d);
                    self.depends_on
                        .get_or_insert_with(|| format!("the file missing at line {line}"));
                    return Ok(());
                }
                Err(d)
            }
        }
    }

    /// Hands out the queued ops that can no longer change.
    fn pop_ready(&mut self) -> Option<Op> {
        if let Some(op) = self.machine.tilt_pending() {
            return Some(op);
        }
        if !self.machine.front_ready() {
            return None;
        }
        let op = self.queue.pop_front()?;
        // ops leave in machine coordinates (datum shift, mirror, rotation, scaling)
        let op = self.machine.output(op);
        let op = self.machine.tilt_output(op); // then the tilted working plane
        self.machine.popped();
        Some(op)
    }
}

impl Iterator for Interpreter {
    type Item = Result<Op, Diagnostic>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(o) = &mut self.other {
            return o.next();
        }
        loop {
            if let Some(op) = self.pop_ready() {
                self.idle_jumps = 0;
                return Some(Ok(op));
            }
            if let Some(d) = self.pending_error.take() {
                self.queue.clear();
                return Some(Err(d));
            }
            if self.machine.probe_request().is_some() {
                // waiting for the machine to measure a probing move
                return None;
            }
            if self.finished || self.done {
                // nothing can change the held element any more
                self.machine.release();
                if let Some(op) = self.pop_ready() {
                    return Some(Ok(op));
                }
                return None;
            }
            if let Err(d) = self.step(Mode::Run) {
                self.finished = true;
                self.machine.release();
                self.pending_error = Some(d);
            }
        }
    }
}
