//! Tools and system data: TOOL CALL, TOOL DEF, FN 18 SYSREAD and FN 15/16 output.
//!
//! FN 18 reads the system data the HEIDENHAIN tables list under these group numbers (ID):
//! 10 NR1 program unit (0 = mm, 1 = inch); 50 tool table, IDX = tool number: NR1 L, NR2 R,
//! NR3 R2, NR4 DL, NR5 DR, NR6 DR2; 20 machine status: NR1 active tool number, NR3
//! tool axis (0 = X, 1 = Y, 2 = Z), NR4 programmed spindle speed, NR5 spindle status (0 M3,
//! 1 M4; this version reads -1 while the spindle stands), NR8 coolant (0 off, 1 on), NR9 feed;
//! 200 tool compensation: NR1 active radius, NR2 active length (deltas included); 240 NR1
//! IDX1..9 nominal position of axis 1..9 (X Y Z A B C U V W) in the reference system; 270 NR1
//! IDX1..9 position in the active coordinate system. This version has no datum shifts, so
//! 240 and 270 read the same last programmed position. Lengths are given in program units.

use super::exec::{ExecError, Machine, here};
use super::parser::{ToolCall, ToolId};
use super::tools::Tool;
use crate::diag::ProgramError;
use crate::klartext::expr::{ParamKind, ParamRef, Value};
use crate::op::{AxisLetter, OpKind, Plane, SpindleDir};

impl Machine {
    /// FN 18: reads one system datum.
    pub(super) fn sysread(
        &self,
        id: Value,
        nr: Value,
        idx: Option<Value>,
    ) -> Result<f64, ExecError> {
        let id = self.params.value(id);
        let nr = self.params.value(nr);
        let idx = idx.map_or(0.0, |v| self.params.value(v));
        let unit = self.unit;
        let unsupported = || {
            here(ProgramError::NotSupported(format!(
                "FN 18 SYSREAD ID{id} NR{nr} IDX{idx}"
            )))
        };
        let whole = |x: f64| (x.fract() == 0.0 && (0.0..1e6).contains(&x)).then_some(x as u32);
        let (Some(id_n), Some(nr_n), Some(idx_n)) = (whole(id), whole(nr), whole(idx)) else {
            return Err(unsupported());
        };
        Ok(match (id_n, nr_n) {
            (10, 1) => {
                if unit == 1.0 {
                    0.0
                } else {
                    1.0
                }
            }
            (20, 1) => f64::from(self.tool.unwrap_or(0)),
            (20, 3) => self.tool_axis.index() as f64,
            (20, 4) => self.speed,
            (20, 5) => match self.spindle {
                SpindleDir::Cw => 0.0,
                SpindleDir::Ccw => 1.0,
                SpindleDir::Off => -1.0,
            },
            (20, 8) => {
                if self.coolant {
                    1.0
                } else {
                    0.0
                }
            }
            (20, 9) => match self.feed {
                Some(f) => f * 60.0 / if unit == 1.0 { 1.0 } else { 2.54 },
                None => 0.0,
            },
            (50, 1..=6) => {
                let Some(t) = self.tools.get(idx_n) else {
                    return Err(here(ProgramError::UnknownTool(idx_n.to_string())));
                };
                let v = match nr_n {
                    1 => t.length,
                    2 => t.radius,
                    3 => t.r2,
                    4 => t.dl,
                    5 => t.dr,
                    _ => t.dr2,
                };
                v / unit
            }
            (200, 1) => self.tool_radius / unit,
            (200, 2) => self.tool_length / unit,
            (240 | 270, 1) => {
                let Some(axis) = idx_n
                    .checked_sub(1)
                    .and_then(|i| AxisLetter::ALL.get(i as usize).copied())
                else {
                    return Err(unsupported());
                };
                let v = self.pos[axis];
                if axis.is_rotary() { v } else { v / unit }
            }
            _ => return Err(unsupported()),
        })
    }

    /// FN 15 / FN 16: the output goes to the log (target `klar::program`), with the values of
    /// the parameters named in FN 15's `Q1/Q2/…` list.
    pub(super) fn print(&self, file: bool, arg: &str) {
        if file {
            tracing::info!(target: "klar::program", "FN 16 F-PRINT {arg}");
            return;
        }
        let mut parts = Vec::new();
        for item in arg.split('/') {
            let item = item.trim();
            let value = item
                .strip_prefix(['Q', 'q'])
                .and_then(|n| n.trim().parse::<u32>().ok())
                .map(|index| {
                    self.params.get(crate::klartext::expr::ParamRef {
                        kind: crate::klartext::expr::ParamKind::Q,
                        index,
                    })
                });
            parts.push(match value {
                Some(v) => format!("{item} = {v}"),
                None => item.trim_matches('"').to_string(),
            });
        }
        tracing::info!(target: "klar::program", "FN 15 PRINT {}", parts.join(", "));
    }

    /// TOOL DEF with L and R defines (or redefines) a tool in the table; without them it
    /// only preselects the next tool, which has no effect on the op stream.
    pub(super) fn tool_def(
        &mut self,
        number: Option<Value>,
        length: Option<Value>,
        radius: Option<Value>,
    ) -> Result<(), ExecError> {
        if length.is_none() && radius.is_none() {
            return Ok(());
        }
        let Some(n) = number.map(|v| self.params.value(v)) else {
            return Err(here(ProgramError::Missing(
                "TOOL DEF with L/R needs a tool number",
            )));
        };
        if !(n >= 0.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX)) {
            return Err(here(ProgramError::OutOfRange(format!(
                "tool number {n} is not a whole number"
            ))));
        }
        let unit = self.unit;
        let len = length.map_or(0.0, |v| self.params.value(v)) * unit;
        let rad = radius.map_or(0.0, |v| self.params.value(v)) * unit;
        self.tools.insert(Tool {
            number: n as u32,
            length: len,
            radius: rad,
            ..Tool::default()
        });
        Ok(())
    }
}

impl Machine {
    pub(super) fn tool_call(
        &mut self,
        tc: &ToolCall,
        text: &[u8],
        emit: &mut impl FnMut(OpKind),
    ) -> Result<(), ExecError> {
        match tc.tool {
            Some(ToolId::Number(v)) => {
                let n = self.params.value(v);
                if !(n >= 0.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX)) {
                    return Err(here(ProgramError::OutOfRange(format!(
                        "tool number {n} is not a whole number from 0 to {}",
                        u32::MAX
                    ))));
                }
                self.tool = Some(n as u32);
                self.tool_name = None;
            }
            Some(ToolId::Name(s, e)) => {
                let name: String = text
                    .get(s..e)
                    .unwrap_or(&[])
                    .iter()
                    .map(|&b| char::from(b))
                    .collect();
                self.tool = self.tools.number_of(&name).or(Some(0));
                self.tool_name = Some(name);
            }
            None => {}
        }
        if let Some(axis) = tc.axis {
            match Plane::from_tool_axis(axis) {
                Some(p) => {
                    self.tool_axis = axis;
                    self.plane = p;
                    // Q109: active tool axis, 0 = X, 1 = Y, 2 = Z
                    self.params.set(
                        ParamRef {
                            kind: ParamKind::Q,
                            index: 109,
                        },
                        axis.index() as f64,
                    );
                }
                None => {
                    return Err(here(ProgramError::NotSupported(format!(
                        "tool axis {axis}"
                    ))));
                }
            }
        }
        let val = |v: Option<Value>| v.map(|v| self.params.value(v));
        let (base_len, base_rad) = match tc.tool {
            None => (self.tool_base.0, self.tool_base.1),
            Some(_) => match self.tools.lookup(self.tool, self.tool_name.as_deref()) {
                Some(t) => (t.length + t.dl, t.radius + t.dr),
                None if self.tools.is_empty() || self.tool == Some(0) => (0.0, 0.0),
                None => {
                    return Err(here(ProgramError::UnknownTool(match &self.tool_name {
                        Some(n) => format!("\"{n}\""),
                        None => self.tool.unwrap_or(0).to_string(),
                    })));
                }
            },
        };
        self.tool_base = (base_len, base_rad);
        let length = base_len + val(tc.dl).unwrap_or(0.0) * self.scale;
        let radius = base_rad + val(tc.dr).unwrap_or(0.0) * self.scale;
        self.tool_length = length;
        self.tool_radius = radius;
        if let Some(f) = val(tc.feed) {
            if !(f > 0.0 && f.is_finite()) {
                return Err(here(ProgramError::OutOfRange(format!(
                    "feed rate F{f} must be positive"
                ))));
            }
            self.fauto = Some(f * self.feed_scale() / 60.0);
        }
        let new_speed = val(tc.speed);
        if let Some(s) = new_speed
            && !(s >= 0.0 && s.is_finite())
        {
            return Err(here(ProgramError::OutOfRange(format!(
                "spindle speed S{s} must not be negative"
            ))));
        }
        emit(OpKind::ToolChange {
            tool: self.tool.unwrap_or(0),
            name: self.tool_name.clone(),
            axis: self.tool_axis,
            length,
            radius,
        });
        // Q108: active tool radius, Q114: active tool length (program units)
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 108,
            },
            radius / self.scale,
        );
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 114,
            },
            length / self.scale,
        );
        if let Some(s) = new_speed {
            self.speed = s;
            if self.spindle != SpindleDir::Off {
                emit(self.spindle_op());
            }
        }
        Ok(())
    }
}
