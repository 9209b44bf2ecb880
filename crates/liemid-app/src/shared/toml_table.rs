//! Input files in TOML: the text parsed into a table with its errors on one line (with the
//! line number), and `Section`, a section with the keys it allows that names the section
//! and key of every unknown key and bad value. Every domain's scenario file uses them.

use liemid::Vec3;
use toml::{Table, Value};

/// The largest magnitude of any number in a scenario file: products of a few such numbers
/// (energies, torques, Newton's Jacobian) stay far from overflow.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// A section of the file with the keys it allows; reports unknown keys and bad values.
pub struct Section<'a> {
    name: &'static str,
    pub table: &'a Table,
}

impl<'a> Section<'a> {
    pub fn new(root: &'a Table, name: &'static str, allowed: &[&str], required: bool) -> Result<Option<Self>, String> {
        let Some(value) = root.get(name) else {
            return if required {
                Err(format!("missing section [{name}]"))
            } else {
                Ok(None)
            };
        };
        let Value::Table(table) = value else {
            return Err(format!(
                "`{name}` must be a section [{name}], found {}",
                value.type_str()
            ));
        };
        for key in table.keys() {
            if !allowed.contains(&key.as_str()) {
                return Err(format!(
                    "[{name}] unknown key `{key}` (allowed: {})",
                    allowed.join(", ")
                ));
            }
        }
        Ok(Some(Section { name, table }))
    }

    pub fn err(&self, key: &str, what: impl std::fmt::Display) -> String {
        format!("[{}] {key}: {what}", self.name)
    }

    pub fn has(&self, key: &str) -> bool {
        self.table.contains_key(key)
    }

    pub fn number_of(&self, key: &str, v: &Value) -> Result<f64, String> {
        let x = match v {
            Value::Float(x) => *x,
            Value::Integer(i) => *i as f64,
            other => return Err(self.err(key, format!("expected a number, found {}", other.type_str()))),
        };
        if !x.is_finite() {
            return Err(self.err(key, format!("must be finite, found {}", liemid::error::Num(x))));
        }
        if x.abs() > MAX_MAGNITUDE {
            return Err(self.err(
                key,
                format!(
                    "{x:e} is too large: values up to {MAX_MAGNITUDE:e} in magnitude are accepted (rescale the units)"
                ),
            ));
        }
        Ok(x)
    }

    pub fn number(&self, key: &str) -> Result<Option<f64>, String> {
        self.table.get(key).map(|v| self.number_of(key, v)).transpose()
    }

    pub fn required_number(&self, key: &str) -> Result<f64, String> {
        self.number(key)?.ok_or_else(|| self.err(key, "is required"))
    }

    pub fn array_of<'v>(&self, key: &str, v: &'v Value, len: usize) -> Result<&'v Vec<Value>, String> {
        match v {
            Value::Array(a) if a.len() == len => Ok(a),
            Value::Array(a) => Err(self.err(key, format!("expected {len} entries, found {}", a.len()))),
            other => Err(self.err(key, format!("expected an array of {len}, found {}", other.type_str()))),
        }
    }

    pub fn vec3_of(&self, key: &str, v: &Value) -> Result<Vec3, String> {
        let a = self.array_of(key, v, 3)?;
        Ok(Vec3::new(
            self.number_of(key, &a[0])?,
            self.number_of(key, &a[1])?,
            self.number_of(key, &a[2])?,
        ))
    }

    pub fn vec3(&self, key: &str) -> Result<Option<Vec3>, String> {
        self.table.get(key).map(|v| self.vec3_of(key, v)).transpose()
    }

    pub fn mat3_of(&self, key: &str, v: &Value) -> Result<[[f64; 3]; 3], String> {
        let rows = self.array_of(key, v, 3)?;
        let mut m = [[0.0; 3]; 3];
        for (i, row) in rows.iter().enumerate() {
            m[i] = self
                .vec3_of(key, row)
                .map_err(|e| format!("{e} (row {})", i + 1))?
                .to_array();
        }
        Ok(m)
    }

    pub fn string(&self, key: &str) -> Result<Option<&'a str>, String> {
        match self.table.get(key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.as_str())),
            Some(other) => Err(self.err(key, format!("expected a string, found {}", other.type_str()))),
        }
    }

    /// A boolean.
    pub fn boolean(&self, key: &str) -> Result<Option<bool>, String> {
        match self.table.get(key) {
            None => Ok(None),
            Some(Value::Boolean(b)) => Ok(Some(*b)),
            Some(other) => Err(self.err(key, format!("expected true or false, found {}", other.type_str()))),
        }
    }

    /// An array of whole numbers of at least 1, of 1 to 3 entries.
    pub fn counts(&self, key: &str) -> Result<Option<Vec<u64>>, String> {
        let Some(v) = self.table.get(key) else {
            return Ok(None);
        };
        let Value::Array(a) = v else {
            return Err(self.err(
                key,
                format!("expected an array of whole numbers, found {}", v.type_str()),
            ));
        };
        if a.is_empty() || a.len() > 3 {
            return Err(self.err(key, format!("expected 1 to 3 entries, found {}", a.len())));
        }
        a.iter()
            .map(|x| match x {
                Value::Integer(i) if *i >= 1 => Ok(*i as u64),
                other => Err(self.err(
                    key,
                    format!("expected whole numbers of at least 1, found {}", shown(other)),
                )),
            })
            .collect::<Result<Vec<u64>, String>>()
            .map(Some)
    }

    pub fn count(&self, key: &str) -> Result<Option<u64>, String> {
        match self.table.get(key) {
            None => Ok(None),
            Some(Value::Integer(i)) if *i >= 1 => Ok(Some(*i as u64)),
            Some(other) => Err(self.err(
                key,
                format!("expected a whole number of at least 1, found {}", shown(other)),
            )),
        }
    }

    /// Exactly one of `keys` (or none when `optional`).
    pub fn one_of(&self, keys: &[&'static str], optional: bool) -> Result<Option<&'static str>, String> {
        let given: Vec<&'static str> = keys.iter().copied().filter(|k| self.has(k)).collect();
        match given.len() {
            0 if optional => Ok(None),
            0 => Err(format!("[{}] needs one of: {}", self.name, keys.join(", "))),
            1 => Ok(Some(given[0])),
            _ => Err(format!(
                "[{}] gives both `{}` and `{}`; use only one",
                self.name, given[0], given[1]
            )),
        }
    }
}

/// Parse TOML text into a table; errors are one line with the line number.
pub fn parse_table(text: &str) -> Result<Table, String> {
    toml::from_str(text).map_err(|e: toml::de::Error| {
        let line = e
            .span()
            .map(|s| format!("line {}: ", line_of(text, s.start)))
            .unwrap_or_default();
        format!("{line}{}", e.message().lines().next().unwrap_or("invalid TOML"))
    })
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// A value for a message: numbers through [`liemid::error::Num`] (no three hundred digits),
/// arrays and tables element by element, and at most 60 characters of it.
pub fn shown(v: &Value) -> String {
    let text = match v {
        Value::Float(x) => liemid::error::Num(*x).to_string(),
        Value::Array(a) => format!("[{}]", a.iter().map(shown).collect::<Vec<_>>().join(", ")),
        Value::Table(t) => format!(
            "{{ {} }}",
            t.iter()
                .map(|(k, x)| format!("{k} = {}", shown(x)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        other => other.to_string(),
    };
    if text.chars().count() <= 60 {
        text
    } else {
        format!(
            "{}… ({} characters)",
            text.chars().take(40).collect::<String>(),
            text.chars().count()
        )
    }
}
