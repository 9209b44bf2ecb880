//! Control input of a run: a constant control, or a table of controls over time held
//! piecewise constant (a zero-order hold, as a controller sampled at the table's times
//! drives MuJoCo through `d.ctrl`): over the step from `t` the control is the table's row
//! with the largest time `≤ t` (the first row before it), the same over the whole step.
//! The table's text is CSV: a header `t,<actuator>,...` naming every actuator of the model
//! once (in any order), then rows of numbers with strictly increasing times.
//!
//! Reference: docs/theory/multibody.md §8.

use crate::error::{Error, Result};

/// Controls over time, one row per time, columns in the model's actuator order.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlTable {
    times: Vec<f64>,
    /// Row-major, `times.len() × actuators`.
    values: Vec<f64>,
    width: usize,
}

fn invalid(reason: String) -> Error {
    Error::InvalidModel { reason }
}

impl ControlTable {
    /// Parse the CSV text against the model's actuator names (`what` names the source in
    /// messages). Blank lines and lines starting with `#` are skipped.
    ///
    /// # Errors
    /// [`Error::InvalidModel`] for a header that does not name each actuator once after
    /// `t`, a row of another width, a value that is not a finite number, times not
    /// strictly increasing, or no row.
    pub fn parse(text: &str, what: &str, actuators: &[String]) -> Result<Self> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let Some((_, header)) = lines.next() else {
            return Err(invalid(format!(
                "{what}: empty (a header line `t,<actuator>,...` and rows)"
            )));
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        if names.first() != Some(&"t") {
            return Err(invalid(format!("{what}: the header's first column must be `t`")));
        }
        let mut column = vec![usize::MAX; actuators.len()];
        for (c, name) in names.iter().enumerate().skip(1) {
            let Some(a) = actuators.iter().position(|n| n == name) else {
                return Err(invalid(format!(
                    "{what}: column `{}` names no actuator of the model (actuators: {})",
                    crate::error::abbreviate(name),
                    actuators.join(", ")
                )));
            };
            if column[a] != usize::MAX {
                return Err(invalid(format!("{what}: actuator `{name}` has two columns")));
            }
            column[a] = c;
        }
        if let Some(a) = column.iter().position(|&c| c == usize::MAX) {
            return Err(invalid(format!("{what}: no column for actuator `{}`", actuators[a])));
        }
        let width = actuators.len();
        let (mut times, mut values) = (Vec::new(), Vec::new());
        let mut row = vec![0.0; names.len()];
        for (line, text) in lines {
            let cells: Vec<&str> = text.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                return Err(invalid(format!(
                    "{what} line {}: {} values, the header has {}",
                    line + 1,
                    cells.len(),
                    names.len()
                )));
            }
            for (x, cell) in row.iter_mut().zip(&cells) {
                *x = cell.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                    invalid(format!(
                        "{what} line {}: `{}` is not a finite number",
                        line + 1,
                        crate::error::abbreviate(cell)
                    ))
                })?;
            }
            if times.last().is_some_and(|&t| row[0] <= t) {
                return Err(invalid(format!(
                    "{what} line {}: time {} does not increase",
                    line + 1,
                    row[0]
                )));
            }
            times.push(row[0]);
            values.extend(column.iter().map(|&c| row[c]));
        }
        if times.is_empty() {
            return Err(invalid(format!("{what}: no rows after the header")));
        }
        Ok(ControlTable { times, values, width })
    }

    /// The control held over the step from `t`: the row with the largest time `≤ t`, the
    /// first row before the table starts.
    #[must_use]
    pub fn at(&self, t: f64) -> &[f64] {
        let k = self.times.partition_point(|&x| x <= t).saturating_sub(1);
        &self.values[k * self.width..(k + 1) * self.width]
    }

    /// The table's times.
    #[must_use]
    pub fn times(&self) -> &[f64] {
        &self.times
    }
}
