//! What `settings_group!` knows of each setting, as data (`SettingInfo`): its `--set` key, label, doc, kind,
//! valid range and panel row. Validation, the viewer's panel, the command line's checks and the docs table
//! (`AoSettings::docs_table`) all read it, so a setting is declared once, in its group.
use std::fmt;

use super::{Invalidates, Mode};
use crate::camera::UpAxis;

/// What kind of value a setting holds (from its Rust type, `SettingValue::KIND`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `bool`: a switch (the panel's checkbox).
    Toggle,
    /// `f32`: a number within its range (the panel's slider).
    Float,
    /// `u32`: a whole number within its range (the panel's slider).
    Integer,
    /// One of a fixed list (`Mode`, `UpAxis`).
    Choice,
    /// Text (the environment), checked by its rule.
    Text,
}

/// How the viewer's panel shows a setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Row {
    /// Drawn from the declaration: a checkbox, a slider over the range, a list.
    Generic,
    /// Drawn by its group's panel code (e.g. the AO radius relative to the scene), with the declared range.
    Custom,
    /// Not in the panel (`--set` and the preferences only).
    Hidden,
}

/// The values a number accepts: `min..=max`, or above `min` (excluded) up to `max`; all finite. An integer may
/// also be held to powers of two.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub min: f64,
    pub max: f64,
    /// `min` itself is refused (a positive number).
    pub above_min: bool,
    pub power_of_two: bool,
}

impl Range {
    /// Whether `v` is a valid value.
    pub fn contains(&self, v: f64) -> bool {
        let low = if self.above_min {
            v > self.min
        } else {
            v >= self.min
        };
        v.is_finite()
            && low
            && v <= self.max
            && (!self.power_of_two || (v >= 1.0 && (v as u64).is_power_of_two() && v.fract() == 0.0))
    }
}

impl fmt::Display for Range {
    /// `0..=180`, `> 0`, `> 0 and <= 86400`, `a power of two in 1024..=268435456`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.power_of_two {
            write!(f, "a power of two in ")?;
        }
        match (self.above_min, self.max.is_finite()) {
            (false, _) => write!(f, "{}..={}", self.min, self.max),
            (true, false) => write!(f, "> {}", self.min),
            (true, true) => write!(f, "> {} and <= {}", self.min, self.max),
        }
    }
}

/// What rejects a text value (`check` in a declaration).
pub type TextRule = fn(&str) -> Result<(), String>;

/// One setting as its group declares it (`FIELDS`). Built in `settings_group!` by `new` and the line's flags,
/// each a method here: `range A..=B`, `above_min`, `power_of_two`, `log`, `label "TEXT"`, `custom`, `hidden`,
/// `needs "SWITCH"`, `check RULE`.
#[derive(Clone, Copy, Debug)]
pub struct SettingInfo {
    /// The field name: its JSON name in the preferences and its `--set` key (the groups are flattened).
    pub name: &'static str,
    /// The name with spaces ("near field"): the default label, and the panel's probe name (`HRTAO_UI_PROBE`).
    pub words: &'static str,
    /// The panel's label and the name in error messages.
    pub label: &'static str,
    /// The field's doc comment, one line per source line.
    pub doc: &'static str,
    pub kind: Kind,
    pub invalidates: Invalidates,
    /// One of our additions: a switch the paper's mode turns off (`paper (false)`).
    pub addition: bool,
    /// Numbers: the valid values (`range`), the validation's and the panel's.
    pub range: Option<Range>,
    /// Numbers: the panel's slider is logarithmic.
    pub log: bool,
    pub row: Row,
    /// The switch of the same group without which this setting does nothing (its row is disabled while off).
    pub needs: Option<&'static str>,
    /// Text: the rule that rejects a value.
    pub rule: Option<TextRule>,
}

impl SettingInfo {
    /// A setting with no range and a generic row (`settings_group!` adds the flags).
    pub const fn new(
        name: &'static str,
        words: &'static str,
        doc: &'static str,
        kind: Kind,
        invalidates: Invalidates,
        addition: bool,
    ) -> Self {
        SettingInfo {
            name,
            words,
            label: words,
            doc,
            kind,
            invalidates,
            addition,
            range: None,
            log: false,
            row: Row::Generic,
            needs: None,
            rule: None,
        }
    }

    pub const fn range(mut self, min: f64, max: f64) -> Self {
        self.range = Some(Range {
            min,
            max,
            above_min: false,
            power_of_two: false,
        });
        self
    }

    pub const fn above_min(mut self) -> Self {
        if let Some(r) = &mut self.range {
            r.above_min = true;
        } else {
            panic!("`above_min` needs a `range` before it");
        }
        self
    }

    pub const fn power_of_two(mut self) -> Self {
        if let Some(r) = &mut self.range {
            r.power_of_two = true;
        } else {
            panic!("`power_of_two` needs a `range` before it");
        }
        self
    }

    pub const fn log(mut self) -> Self {
        self.log = true;
        self
    }

    pub const fn label(mut self, label: &'static str) -> Self {
        self.label = label;
        self
    }

    pub const fn custom(mut self) -> Self {
        self.row = Row::Custom;
        self
    }

    pub const fn hidden(mut self) -> Self {
        self.row = Row::Hidden;
        self
    }

    pub const fn needs(mut self, switch: &'static str) -> Self {
        self.needs = Some(switch);
        self
    }

    pub const fn check(mut self, rule: TextRule) -> Self {
        self.rule = Some(rule);
        self
    }

    /// The doc as one paragraph (the panel's hover text, the docs table).
    pub fn text(&self) -> String {
        self.doc.split_whitespace().collect::<Vec<_>>().join(" ")
    }

    /// Whether `v` is valid; the error names the setting and its range.
    pub fn check_number(&self, v: f64) -> Result<(), String> {
        match self.range {
            Some(r) if !r.contains(v) => {
                Err(format!("{} (`{}`) must be {r}, got {v}", self.label, self.name))
            }
            _ => Ok(()),
        }
    }

    /// Whether the text `v` passes the setting's rule.
    pub fn check_text(&self, v: &str) -> Result<(), String> {
        match self.rule {
            Some(rule) => rule(v).map_err(|e| format!("{} (`{}`): {e}", self.label, self.name)),
            None => Ok(()),
        }
    }
}

/// A mutable reference to one setting's value, by kind: what the panel edits generically
/// (`AoSettings::fields_mut`).
pub enum SettingRef<'a> {
    Bool(&'a mut bool),
    F32(&'a mut f32),
    U32(&'a mut u32),
    Mode(&'a mut Mode),
    Text(&'a mut String),
    Axis(&'a mut UpAxis),
}

/// The types a setting may have: each gives its kind, a `SettingRef` and its number or text for validation.
pub trait SettingValue {
    const KIND: Kind;
    fn setting_ref(&mut self) -> SettingRef<'_>;
    fn number(&self) -> Option<f64> {
        None
    }
    fn text(&self) -> Option<&str> {
        None
    }
}

impl SettingValue for bool {
    const KIND: Kind = Kind::Toggle;
    fn setting_ref(&mut self) -> SettingRef<'_> {
        SettingRef::Bool(self)
    }
}

impl SettingValue for f32 {
    const KIND: Kind = Kind::Float;
    fn setting_ref(&mut self) -> SettingRef<'_> {
        SettingRef::F32(self)
    }
    fn number(&self) -> Option<f64> {
        Some(*self as f64)
    }
}

impl SettingValue for u32 {
    const KIND: Kind = Kind::Integer;
    fn setting_ref(&mut self) -> SettingRef<'_> {
        SettingRef::U32(self)
    }
    fn number(&self) -> Option<f64> {
        Some(*self as f64)
    }
}

impl SettingValue for Mode {
    const KIND: Kind = Kind::Choice;
    fn setting_ref(&mut self) -> SettingRef<'_> {
        SettingRef::Mode(self)
    }
}

impl SettingValue for String {
    const KIND: Kind = Kind::Text;
    fn setting_ref(&mut self) -> SettingRef<'_> {
        SettingRef::Text(self)
    }
    fn text(&self) -> Option<&str> {
        Some(self)
    }
}

impl SettingValue for UpAxis {
    const KIND: Kind = Kind::Choice;
    fn setting_ref(&mut self) -> SettingRef<'_> {
        SettingRef::Axis(self)
    }
}

/// `name` with every `_` a space, as `N` bytes (the default label, made at compile time).
pub const fn spaced<const N: usize>(name: &str) -> [u8; N] {
    let bytes = name.as_bytes();
    let mut out = [0u8; N];
    let mut i = 0;
    while i < N {
        out[i] = if bytes[i] == b'_' { b' ' } else { bytes[i] };
        i += 1;
    }
    out
}

const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The declaration's rules, checked when the crate compiles (`settings_group!` calls it on every group): every
/// setting has a doc; a number has a range with min <= max, and only a number has one; a slider the panel
/// draws from the declaration spans a closed range; a text's rule is a text's; `needs` names a switch of the
/// same group.
pub const fn check_fields(fields: &[SettingInfo]) {
    let mut i = 0;
    while i < fields.len() {
        let f = &fields[i];
        if f.doc.is_empty() {
            panic!("{}", f.name);
        }
        let number = matches!(f.kind, Kind::Float | Kind::Integer);
        match f.range {
            Some(r) => {
                if !number {
                    panic!("only a number has a range");
                }
                if r.min.is_nan() || r.max.is_nan() || r.min > r.max {
                    panic!("a range's min is above its max");
                }
                if matches!(f.row, Row::Generic) && (r.above_min || !r.max.is_finite()) {
                    panic!("a slider needs a closed range: give it one, or mark the setting `custom` or `hidden`");
                }
            }
            None => {
                if number {
                    panic!("a number setting needs a `range`");
                }
            }
        }
        if f.log && !number {
            panic!("only a number has a logarithmic slider");
        }
        if f.rule.is_some() && !matches!(f.kind, Kind::Text) {
            panic!("only a text has a `check` rule");
        }
        if let Some(switch) = f.needs {
            let mut found = false;
            let mut j = 0;
            while j < fields.len() {
                if same(fields[j].name, switch) && matches!(fields[j].kind, Kind::Toggle) {
                    found = true;
                }
                j += 1;
            }
            if !found {
                panic!("`needs` names no switch of the group");
            }
        }
        i += 1;
    }
}
