//! User-facing AO settings, grouped by what they govern, with the paper's names.
//!
//! Each group (`map`, `filter`, `still`, `young`, `edits`, `display`, `light`) is declared with
//! `settings_group!`: one line per setting gives its default, what a change of it invalidates (`Invalidates`),
//! its value in the paper's mode (`AoSettings::paper`) and, as flags, its valid range, its label and its panel
//! row (`SettingInfo`, `info.rs`). From that line alone follow its validation (`AoSettings::validate`), its
//! panel row (the viewer draws `fields_mut` generically), its `--set` key and the command line's checks, and its
//! row of the settings table in docs/command-line.md (`AoSettings::docs_table`). Each group file also owns its
//! share of the GPU parameters (`FrameGlobals`). Our additions to the paper are each one `bool` (off = `false`,
//! the paper); their tuning constants live beside them.
//!
//! In JSON (prefs, `--set`, bench results) the groups are flattened: `{"ao_radius": 2, "contact_detail": false}`.
use serde::{Deserialize, Serialize};

use crate::gpu::FrameGlobals;

mod display;
mod edits;
mod filter;
mod info;
mod light;
mod map;
mod mode;
mod still;
mod young;

pub use display::{DisplaySettings, CREASE_DEG_RANGE};
pub use edits::EditSettings;
pub use filter::{FilterSettings, FILTER_SIGMA, MAX_FILTER_ITERATIONS};
pub use info::{check_fields, spaced, Kind, Range, Row, SettingInfo, SettingRef, SettingValue, TextRule};
pub use light::{LightSettings, INTENSITY_RANGE};
pub use map::{MapSettings, MAX_CACHE_LIFETIME_S, MAX_CELL_FRACTION, MAX_PROBE, NORMAL_BIN_OFFSET};
pub use mode::Mode;
pub use still::{frame_smoothing, StillSettings, PRIOR_RAYS, RESIDUAL_SIGMA, STILL_SMOOTHING};
pub use young::YoungMapSettings;

/// What a change of a setting invalidates (`AoSettings::invalidates`), from least to most. A frame's change as a
/// whole (camera, scene, settings) is decided in `frame::Change`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Invalidates {
    /// Nothing shown changes: the still image keeps accumulating.
    Nothing,
    /// The still image restarts; the hash map keeps its cells (they hold the same AO).
    StillImage,
    /// What a cell holds or where it lives changes: every cell of the map is invalidated (a new F, eq. 6).
    WholeMap,
}

/// Declares a group of settings, one line each:
///
/// ```text
/// /// Doc: the panel's hover text and the docs table's.
/// name: Type = default, Class, paper keep|(value) [, flag [arg]]*;
/// ```
///
/// `Class` is the field's `Invalidates`; `paper keep` keeps the user's value in the paper's mode, `paper (v)`
/// sets `v` (a `bool` so set is one of our additions). The flags are `SettingInfo`'s builder methods: `range
/// A..=B` (required for a number: validation, slider, docs), `above_min`, `power_of_two`, `log` (slider),
/// `label "TEXT"` (else the name with spaces), `custom` (its group's panel code draws it), `hidden` (not in the
/// panel), `needs "SWITCH"` (disabled while that switch of the group is off), `check RULE` (a text's).
///
/// It writes the struct (serde-defaulted), its `Default`, `FIELDS` (each field's `SettingInfo`, checked when
/// the crate compiles: `check_fields`), `CLASSES`, `invalidates`, `paper`, `validate` (every range and rule),
/// `fields_mut` (each field's `SettingRef`, for the panel) and `additions_mut`.
macro_rules! settings_group {
    (@paper $v:expr, keep) => { $v.clone() };
    (@paper $v:expr, ($p:expr)) => { $p };
    (@sets keep) => { false };
    (@sets ($p:expr)) => { true };
    (@flag $i:ident, range $r:expr) => { $i.range(*$r.start() as f64, *$r.end() as f64) };
    (@flag $i:ident, $flag:ident $($arg:expr)?) => { $i.$flag($($arg)?) };
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $(
                $(#[doc = $doc:literal])*
                $field:ident : $ty:ty = $default:expr, $class:ident, paper $paper:tt $(, $flag:ident $($arg:expr)?)* ;
            )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(default)]
        pub struct $name {
            $( $(#[doc = $doc])* pub $field: $ty, )*
        }

        impl Default for $name {
            fn default() -> Self {
                $name { $( $field: $default, )* }
            }
        }

        const _: () = $crate::settings::check_fields($name::FIELDS);

        impl $name {
            /// Every field as declared: key, label, doc, kind, range, panel row.
            pub const FIELDS: &'static [$crate::settings::SettingInfo] = &[$({
                const WORDS: [u8; stringify!($field).len()] = $crate::settings::spaced(stringify!($field));
                let words = match core::str::from_utf8(&WORDS) {
                    Ok(w) => w,
                    Err(_) => panic!("a field name is ASCII"),
                };
                let kind = <$ty as $crate::settings::SettingValue>::KIND;
                let info = $crate::settings::SettingInfo::new(
                    stringify!($field),
                    words,
                    concat!($($doc, "\n",)*),
                    kind,
                    $crate::settings::Invalidates::$class,
                    matches!(kind, $crate::settings::Kind::Toggle) && settings_group!(@sets $paper),
                );
                $( let info = settings_group!(@flag info, $flag $($arg)?); )*
                info
            },)*];

            /// Every field with what its change invalidates.
            pub const CLASSES: &'static [(&'static str, $crate::settings::Invalidates)] =
                &[$( (stringify!($field), $crate::settings::Invalidates::$class), )*];

            /// The largest class of the fields that differ from `new`.
            pub fn invalidates(&self, new: &Self) -> $crate::settings::Invalidates {
                let mut class = $crate::settings::Invalidates::Nothing;
                $(
                    if self.$field != new.$field {
                        class = class.max($crate::settings::Invalidates::$class);
                    }
                )*
                class
            }

            /// This group as the paper publishes it: our additions off, the paper's parameters kept.
            pub fn paper(&self) -> Self {
                $name { $( $field: settings_group!(@paper self.$field, $paper), )* }
            }

            /// Checks every field against its declaration (range, rule); the message names the setting.
            pub fn validate(&self) -> Result<(), String> {
                let numbers: &[Option<f64>] = &[$( $crate::settings::SettingValue::number(&self.$field), )*];
                let texts: &[Option<&str>] = &[$( $crate::settings::SettingValue::text(&self.$field), )*];
                for ((info, n), t) in Self::FIELDS.iter().zip(numbers).zip(texts) {
                    if let Some(n) = n {
                        info.check_number(*n)?;
                    }
                    if let Some(t) = t {
                        info.check_text(t)?;
                    }
                }
                Ok(())
            }

            /// Every field with a mutable reference to its value, in declaration order (the panel's rows).
            pub fn fields_mut(
                &mut self,
            ) -> Vec<(&'static $crate::settings::SettingInfo, $crate::settings::SettingRef<'_>)> {
                let refs: Vec<$crate::settings::SettingRef<'_>> =
                    vec![$( $crate::settings::SettingValue::setting_ref(&mut self.$field), )*];
                Self::FIELDS.iter().zip(refs).collect()
            }

            /// Our additions in this group (the `bool` fields the paper's mode sets), with their docs.
            pub fn additions_mut(&mut self) -> Vec<$crate::settings::Addition<'_>> {
                $crate::settings::Addition::of(self.fields_mut())
            }
        }
    };
}
pub(crate) use settings_group;

/// One of our additions as a group lists it (`additions_mut`): its field name, its doc and its switch.
pub struct Addition<'a> {
    pub name: &'static str,
    /// The field's doc comment, one line per source line.
    pub doc: &'static str,
    pub on: &'a mut bool,
}

impl<'a> Addition<'a> {
    /// The additions among a group's fields.
    pub fn of(fields: Vec<(&'static SettingInfo, SettingRef<'a>)>) -> Vec<Addition<'a>> {
        fields
            .into_iter()
            .filter_map(|(info, value)| match value {
                SettingRef::Bool(on) if info.addition => Some(Addition {
                    name: info.name,
                    doc: info.doc,
                    on,
                }),
                _ => None,
            })
            .collect()
    }
}

impl Addition<'_> {
    /// The field name as a label ("near_field" -> "near field").
    pub fn label(&self) -> String {
        self.name.replace('_', " ")
    }

    /// The doc as one paragraph.
    pub fn text(&self) -> String {
        self.doc.split_whitespace().collect::<Vec<_>>().join(" ")
    }
}

/// All AO settings: one value, in the viewer's preferences and applied to the renderer with each frame
/// (`frame::FrameDesc`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct AoSettings {
    /// The paper's hash map and its sampling (§1–4, §6).
    #[serde(flatten)]
    pub map: MapSettings,
    /// The adaptive à-trous filter (§5).
    #[serde(flatten)]
    pub filter: FilterSettings,
    /// Still-camera refinement (ours): a resting view converges to the ray-traced image.
    #[serde(flatten)]
    pub still: StillSettings,
    /// The first frames of a young map (ours): detail and noise while cells hold few rays.
    #[serde(flatten)]
    pub young: YoungMapSettings,
    /// How scene edits invalidate the map (eq. 6, and our local edits).
    #[serde(flatten)]
    pub edits: EditSettings,
    /// What is shown and how: mode, shading, feature edges.
    #[serde(flatten)]
    pub display: DisplaySettings,
    /// How the model is lit: the AO look or the sky light.
    #[serde(flatten)]
    pub light: LightSettings,
}

impl AoSettings {
    /// Every addition of ours, group by group: the switches the paper's mode turns off (the panel's checkboxes,
    /// the ablation's rows).
    pub fn additions_mut(&mut self) -> Vec<Addition<'_>> {
        let mut list = self.map.additions_mut();
        list.extend(self.filter.additions_mut());
        list.extend(self.still.additions_mut());
        list.extend(self.young.additions_mut());
        list.extend(self.edits.additions_mut());
        list.extend(self.display.additions_mut());
        list.extend(self.light.additions_mut());
        list
    }

    /// The names of our additions ("near field", ...), in the order of `additions_mut`: where the paper's mode
    /// is described to a user, the list follows the settings.
    pub fn addition_names() -> Vec<String> {
        AoSettings::default()
            .additions_mut()
            .iter()
            .map(Addition::label)
            .collect()
    }

    /// The published technique with these parameters: every group's `paper()` (our additions off, eq. (5)'s
    /// bins as published), so `hrtao bench` can run both side by side.
    pub fn paper(&self) -> AoSettings {
        AoSettings {
            map: self.map.paper(),
            filter: self.filter.paper(),
            still: self.still.paper(),
            young: self.young.paper(),
            edits: self.edits.paper(),
            display: self.display.paper(),
            light: self.light.paper(),
        }
    }

    /// What changing these settings to `new` invalidates: the largest class of the fields that differ.
    pub fn invalidates(&self, new: &AoSettings) -> Invalidates {
        [
            self.map.invalidates(&new.map),
            self.filter.invalidates(&new.filter),
            self.still.invalidates(&new.still),
            self.young.invalidates(&new.young),
            self.edits.invalidates(&new.edits),
            self.display.invalidates(&new.display),
            self.light.invalidates(&new.light),
        ]
        .into_iter()
        .max()
        .unwrap_or(Invalidates::Nothing)
    }

    /// Every setting (its JSON name) with its class, group by group.
    pub fn classes() -> Vec<(&'static str, Invalidates)> {
        [
            MapSettings::CLASSES,
            FilterSettings::CLASSES,
            StillSettings::CLASSES,
            YoungMapSettings::CLASSES,
            EditSettings::CLASSES,
            DisplaySettings::CLASSES,
            LightSettings::CLASSES,
        ]
        .concat()
    }

    /// Whether still frames accumulate (per-pixel RTAO; HRTAO and AO off with refinement). Must agree with
    /// composite.comp.
    pub fn accumulates(&self) -> bool {
        match self.display.mode {
            Mode::Rtao => true,
            Mode::Hrtao | Mode::NoAo => self.still.refine,
            _ => false,
        }
    }

    /// The AO radius R (shorthand: most callers only set it and the budget).
    pub fn with_radius(mut self, ao_radius: f32) -> AoSettings {
        self.map.ao_radius = ao_radius;
        self
    }

    /// These settings with the fields of the JSON object `overrides` replaced, e.g. `{"near_field": false}`
    /// (`--set` of the command line and the development examples). An unknown field or a value of the wrong
    /// type is an error; the result is validated.
    pub fn with_overrides(&self, overrides: &str) -> Result<AoSettings, String> {
        let fields: serde_json::Map<String, serde_json::Value> =
            serde_json::from_str(overrides).map_err(|e| format!("settings overrides {overrides:?}: {e}"))?;
        let s = self
            .with_fields(fields)
            .map_err(|e| format!("settings overrides: {e}"))?;
        s.validate()?;
        Ok(s)
    }

    fn with_fields(&self, fields: serde_json::Map<String, serde_json::Value>) -> Result<AoSettings, String> {
        let mut v = serde_json::to_value(self).map_err(|e| e.to_string())?;
        for (k, x) in fields {
            match v.get_mut(&k) {
                Some(slot) => *slot = x,
                None => return Err(format!("no setting {k:?}")),
            }
        }
        serde_json::from_value(v).map_err(|e| e.to_string())
    }

    /// Settings from a JSON object written by another version (the viewer's preferences): each known field
    /// that is valid replaces the default; the others are skipped and named in the returned list.
    pub fn from_json_lenient(value: &serde_json::Value) -> (AoSettings, Vec<String>) {
        let mut s = AoSettings::default();
        let mut skipped = Vec::new();
        if let Some(fields) = value.as_object() {
            for (k, x) in fields {
                let one = serde_json::Map::from_iter([(k.clone(), x.clone())]);
                match s.with_fields(one) {
                    Ok(next) if next.validate().is_ok() => s = next,
                    _ => skipped.push(k.clone()),
                }
            }
        }
        (s, skipped)
    }

    /// Checks every setting against its declaration (its range or rule); the message names the setting.
    pub fn validate(&self) -> Result<(), String> {
        self.map.validate()?;
        self.filter.validate()?;
        self.still.validate()?;
        self.young.validate()?;
        self.edits.validate()?;
        self.display.validate()?;
        self.light.validate()
    }

    /// Every setting as declared, group by group (the order of the panel and of the docs table).
    pub fn fields() -> Vec<&'static SettingInfo> {
        [
            MapSettings::FIELDS,
            FilterSettings::FIELDS,
            StillSettings::FIELDS,
            YoungMapSettings::FIELDS,
            EditSettings::FIELDS,
            DisplaySettings::FIELDS,
            LightSettings::FIELDS,
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    /// The declaration of the setting whose JSON name (`--set` key) is `name`.
    pub fn field(name: &str) -> Option<&'static SettingInfo> {
        AoSettings::fields().into_iter().find(|f| f.name == name)
    }

    /// Every setting with a mutable reference to its value, group by group.
    pub fn fields_mut(&mut self) -> Vec<(&'static SettingInfo, SettingRef<'_>)> {
        let mut list = self.map.fields_mut();
        list.extend(self.filter.fields_mut());
        list.extend(self.still.fields_mut());
        list.extend(self.young.fields_mut());
        list.extend(self.edits.fields_mut());
        list.extend(self.display.fields_mut());
        list.extend(self.light.fields_mut());
        list
    }

    /// The settings table of docs/command-line.md, one row per setting from its declaration: `--set` key,
    /// default, valid values, what a change invalidates, panel label, doc (tests/settings_declared.rs holds
    /// the page to it).
    pub fn docs_table() -> String {
        let defaults = serde_json::to_value(AoSettings::default()).unwrap_or_default();
        let mut t = String::from(
            "| `--set` key | default | valid values | a change restarts | panel | what it sets |\n\
             |---|---|---|---|---|---|\n",
        );
        let mut settings = AoSettings::default();
        for (f, value) in settings.fields_mut() {
            let json = |v: serde_json::Value| format!("`{}`", v.as_str().unwrap_or_default());
            let values = match (f.range, value) {
                (Some(r), _) => r.to_string(),
                (None, SettingRef::Bool(_)) => "true, false".to_string(),
                (None, SettingRef::Mode(_)) => Mode::ALL.map(|m| json(serde_json::json!(m))).join(", "),
                (None, SettingRef::Axis(_)) => crate::camera::UpAxis::ALL
                    .map(|a| json(serde_json::json!(a)))
                    .join(", "),
                _ => "text".to_string(),
            };
            let restarts = match f.invalidates {
                Invalidates::Nothing => "nothing",
                Invalidates::StillImage => "the still image",
                Invalidates::WholeMap => "the whole map",
            };
            let panel = match f.row {
                Row::Hidden => "—".to_string(),
                _ if f.log => format!("{} (log)", f.label),
                _ => f.label.to_string(),
            };
            t.push_str(&format!(
                "| `{}` | `{}` | {values} | {restarts} | {panel} | {} |\n",
                f.name,
                defaults[f.name],
                f.text().replace('|', "\\|")
            ));
        }
        t
    }

    /// Writes the settings' share of the frame's GPU parameters, group by group (the young map's additions have
    /// their flag and push constants from `crate::additions`, their constants in their shaders).
    pub fn write_gpu(&self, g: &mut FrameGlobals) {
        self.map.write_gpu(g);
        self.filter.write_gpu(g);
        self.still.write_gpu(g);
        self.display.write_gpu(g);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_named_fields_and_reject_unknown_or_invalid_ones() {
        let base = AoSettings::default();
        let s = base
            .with_overrides(r#"{"refine": false, "filter_iterations": 3, "ao_radius": 3}"#)
            .unwrap();
        assert_eq!(
            (s.still.refine, s.filter.filter_iterations, s.map.ao_radius),
            (false, 3, 3.0)
        );
        assert_eq!(s.map.s_p, base.map.s_p);
        let err = base.with_overrides(r#"{"refnie": false}"#).unwrap_err();
        assert!(err.contains("refnie"), "{err}");
        assert!(base.with_overrides(r#"{"refine": "no"}"#).is_err());
        let err = base.with_overrides(r#"{"ao_radius": -1}"#).unwrap_err();
        assert!(err.contains("AO radius"), "{err}");
        assert!(base.with_overrides("not json").is_err());
    }

    #[test]
    fn settings_of_another_version_keep_what_is_valid() {
        let old = serde_json::json!({"ao_radius": 2.5, "pooled_residual": 16.0, "gone": 1, "s_p": -1});
        let (s, skipped) = AoSettings::from_json_lenient(&old);
        assert_eq!(s.map.ao_radius, 2.5);
        assert_eq!(s.map.s_p, AoSettings::default().map.s_p);
        assert_eq!(skipped, ["gone", "pooled_residual", "s_p"]);
    }

    #[test]
    fn every_setting_has_one_class_and_a_unique_json_name() {
        let classes = AoSettings::classes();
        let json = serde_json::to_value(AoSettings::default()).unwrap();
        let names: Vec<&str> = json.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        assert_eq!(
            names.len(),
            classes.len(),
            "a setting without a class, or one named twice"
        );
        for (name, _) in &classes {
            assert!(names.contains(name), "{name} is not a JSON field");
        }
    }

    #[test]
    fn the_paper_mode_turns_every_addition_off_and_keeps_the_papers_parameters() {
        let ours = AoSettings::default().with_radius(7.0);
        let p = ours.paper();
        assert_eq!(p.map.ao_radius, 7.0);
        assert_eq!((p.map.s_p, p.map.s_nd, p.map.max_samples), (4.0, 3.0, 1000));
        assert!(!p.map.offset_bins && !p.map.cell_cap && !p.filter.variance_filter);
        assert!(!p.still.refine && !p.edits.local_edits);
        assert_eq!(p.young, YoungMapSettings::paper(&ours.young));
        let young = serde_json::to_value(&p.young).unwrap();
        for (k, v) in young.as_object().unwrap() {
            assert_eq!(v, &serde_json::json!(false), "{k} is on in the paper's mode");
        }
    }

    /// The panel's checkboxes (`additions_mut`) are exactly the switches the paper's mode turns off, each with
    /// its doc, and each switches its own field.
    #[test]
    fn the_additions_are_the_switches_the_papers_mode_turns_off() {
        let mut s = AoSettings::default();
        let mut names = Vec::new();
        let mut count = 0;
        for a in s.additions_mut() {
            assert!(a.text().len() > 40, "{}: no doc", a.name);
            names.push(a.name);
            *a.on = !*a.on;
            count += 1;
        }
        names.sort();
        let flipped = serde_json::to_value(&s).unwrap();
        let (ours, paper) = (
            serde_json::to_value(AoSettings::default()).unwrap(),
            serde_json::to_value(AoSettings::default().paper()).unwrap(),
        );
        let mut off_in_paper: Vec<&str> = ours
            .as_object()
            .unwrap()
            .iter()
            // A switch the paper's mode turns off (a switch it keeps, as the sky light, is not ours to ablate).
            .filter(|(k, v)| **v == serde_json::json!(true) && paper[k.as_str()] == serde_json::json!(false))
            .map(|(k, _)| k.as_str())
            .collect();
        off_in_paper.sort();
        assert_eq!(names, off_in_paper);
        let changed = ours
            .as_object()
            .unwrap()
            .iter()
            .filter(|(k, v)| flipped[k.as_str()] != **v)
            .count();
        assert_eq!(changed, count, "each checkbox switches its own field");
    }

    /// The value `v` of setting `name` in otherwise default settings, through `--set`'s path.
    fn set(name: &str, v: f64) -> Result<AoSettings, String> {
        let integer = AoSettings::field(name).is_some_and(|f| f.kind == Kind::Integer);
        let v = match integer {
            true if v >= 0.0 => serde_json::json!(v as u64),
            _ => serde_json::json!(v),
        };
        AoSettings::default().with_overrides(&serde_json::json!({ name: v }).to_string())
    }

    /// Validation is the declaration: every number accepts its range's ends (its min unless excluded) and
    /// refuses a step past either, naming the setting; the defaults are valid.
    #[test]
    fn every_number_validates_exactly_its_declared_range() {
        assert_eq!(AoSettings::default().validate(), Ok(()));
        let mut numbers = 0;
        for f in AoSettings::fields() {
            let Some(r) = f.range else { continue };
            numbers += 1;
            let integer = f.kind == Kind::Integer;
            let step = |v: f64| if integer { 1.0 } else { v.abs().max(1.0) * 1e-3 };
            if r.max.is_finite() {
                assert!(
                    set(f.name, r.max).is_ok(),
                    "{}: its max {} refused",
                    f.name,
                    r.max
                );
                let e = set(f.name, r.max + step(r.max)).unwrap_err();
                assert!(e.contains(f.name) && e.contains(f.label), "{e}");
            }
            if r.above_min {
                assert!(
                    set(f.name, r.min).is_err(),
                    "{}: its excluded min accepted",
                    f.name
                );
                assert!(set(f.name, r.min + step(r.min)).is_ok(), "{}", f.name);
            } else {
                assert!(
                    set(f.name, r.min).is_ok(),
                    "{}: its min {} refused",
                    f.name,
                    r.min
                );
                if !(integer && r.min == 0.0) {
                    assert!(
                        set(f.name, r.min - step(r.min)).is_err(),
                        "{}: below its min",
                        f.name
                    );
                }
            }
            if r.power_of_two {
                assert!(
                    set(f.name, r.min * 3.0).is_err(),
                    "{}: not a power of two",
                    f.name
                );
            }
            let default = serde_json::to_value(AoSettings::default()).unwrap()[f.name]
                .as_f64()
                .unwrap();
            assert!(r.contains(default), "{}: default {default} outside {r}", f.name);
        }
        assert!(numbers >= 14, "{numbers} numbers");
        for (name, v) in [("s_p", f64::NAN), ("environment_rotation", f64::INFINITY)] {
            let mut s = AoSettings::default();
            for (f, value) in s.fields_mut() {
                if let (true, SettingRef::F32(x)) = (f.name == name, value) {
                    *x = v as f32;
                }
            }
            assert!(s.validate().unwrap_err().contains(name), "{name} = {v}");
        }
        let e = AoSettings::default()
            .with_overrides(r#"{"environment": "sky.png"}"#)
            .unwrap_err();
        assert!(e.contains("environment"), "{e}");
    }

    /// The declaration, whole: one entry per JSON field (its `--set` key), in the JSON's order, each with a doc
    /// and a label; every number with a range (also checked when the crate compiles, `check_fields`); the
    /// additions are the switches with `paper (false)`; a `needs` names a switch of its group.
    #[test]
    fn every_setting_is_declared_with_its_doc_range_and_row() {
        let json = serde_json::to_value(AoSettings::default()).unwrap();
        let keys: Vec<&str> = json.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        let mut names: Vec<&str> = AoSettings::fields().iter().map(|f| f.name).collect();
        let declared = names.clone();
        names.sort();
        let mut sorted_keys = keys.clone();
        sorted_keys.sort();
        assert_eq!(names, sorted_keys, "the declared settings are the JSON fields");
        let classes: Vec<&str> = AoSettings::classes().iter().map(|(n, _)| *n).collect();
        assert_eq!(declared, classes);
        for f in AoSettings::fields() {
            assert!(f.text().len() >= 20, "{}: no doc", f.name);
            assert!(
                !f.label.is_empty() && f.words == f.name.replace('_', " "),
                "{}",
                f.name
            );
            let number = matches!(f.kind, Kind::Float | Kind::Integer);
            assert_eq!(
                f.range.is_some(),
                number,
                "{}: a range exactly for a number",
                f.name
            );
            assert_eq!(
                f.addition,
                f.kind == Kind::Toggle && AoSettings::addition_names().contains(&f.words.to_string()),
                "{}",
                f.name
            );
            if let Some(n) = f.needs {
                let switch = AoSettings::field(n).unwrap();
                assert_eq!(switch.kind, Kind::Toggle, "{}", f.name);
            }
        }
        assert_eq!(AoSettings::field("crease_deg").unwrap().needs, Some("edges"));
        assert!(AoSettings::field("nope").is_none());
    }

    /// `fields_mut` hands out each field's own value: writing through it changes that JSON field only.
    #[test]
    fn fields_mut_reaches_each_field() {
        let mut s = AoSettings::default();
        let before = serde_json::to_value(&s).unwrap();
        let mut count = 0;
        for (_, value) in s.fields_mut() {
            match value {
                SettingRef::Bool(b) => *b = !*b,
                SettingRef::F32(v) => *v += 1.0,
                SettingRef::U32(v) => *v += 1,
                SettingRef::Mode(m) => *m = Mode::Rtao,
                SettingRef::Text(t) => t.push('x'),
                SettingRef::Axis(a) => *a = crate::camera::UpAxis::NegZ,
            }
            count += 1;
        }
        let after = serde_json::to_value(&s).unwrap();
        let changed = before
            .as_object()
            .unwrap()
            .iter()
            .filter(|(k, v)| after[k.as_str()] != **v)
            .count();
        assert_eq!(
            (changed, count),
            (AoSettings::fields().len(), AoSettings::fields().len())
        );
    }

    /// The docs table has one row per `--set` key, with its declared range and its default.
    #[test]
    fn the_docs_table_lists_every_key_with_its_range_and_default() {
        let table = AoSettings::docs_table();
        let defaults = serde_json::to_value(AoSettings::default()).unwrap();
        assert_eq!(table.lines().count(), 2 + AoSettings::fields().len());
        for f in AoSettings::fields() {
            let row = table
                .lines()
                .find(|l| l.starts_with(&format!("| `{}` |", f.name)))
                .unwrap_or_else(|| panic!("no row for {}", f.name));
            assert!(row.contains(&format!("`{}`", defaults[f.name])), "{row}");
            if let Some(r) = f.range {
                assert!(row.contains(&r.to_string()), "{row}");
            }
        }
    }
}
