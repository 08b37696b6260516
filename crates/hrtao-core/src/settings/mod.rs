//! User-facing AO settings, grouped by what they govern, with the paper's names.
//!
//! Each group (`map`, `filter`, `still`, `young`, `edits`, `display`) is declared with `settings_group!`, which
//! writes next to every setting its default, what a change of it invalidates (`Invalidates`) and its value in
//! the paper's mode (`AoSettings::paper`): a new setting cannot be added without them. Each group file also
//! owns the group's validation and its share of the GPU parameters (`FrameGlobals`). Our additions to the paper
//! are each one `bool` (off = `false`, the paper); their tuning constants live beside them.
//!
//! In JSON (prefs, `--set`, bench results) the groups are flattened: `{"ao_radius": 2, "contact_detail": false}`.
use serde::{Deserialize, Serialize};

use crate::gpu::FrameGlobals;

mod display;
mod edits;
mod filter;
mod light;
mod map;
mod mode;
mod still;
mod young;

pub use display::{DisplaySettings, CREASE_DEG_RANGE};
pub use edits::EditSettings;
pub use filter::{FilterSettings, FILTER_SIGMA, MAX_FILTER_ITERATIONS};
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

/// Declares a group of settings: the struct (serde-defaulted), its `Default`, `CLASSES` (each field's
/// `Invalidates`), `invalidates` (the largest class of the fields that differ) and `paper` (the published
/// technique's values: `keep` = the user's value, `(expr)` = that value).
macro_rules! settings_group {
    (@paper $v:expr, keep) => { $v.clone() };
    (@paper $v:expr, ($p:expr)) => { $p };
    (@addition $list:ident, $name:expr, $doc:expr, $f:expr, keep) => {};
    (@addition $list:ident, $name:expr, $doc:expr, $f:expr, ($p:expr)) => {
        if let Some(on) = $crate::settings::AsToggle::as_toggle(&mut $f) {
            $list.push($crate::settings::Addition { name: $name, doc: $doc, on });
        }
    };
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $(
                $(#[doc = $doc:literal])*
                $field:ident : $ty:ty = $default:expr, $class:ident, paper $paper:tt;
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

        impl $name {
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

            /// Our additions in this group (the `bool` fields the paper's mode sets), with their docs: the
            /// panel shows each as a checkbox, so adding or deleting one does not touch the panel.
            pub fn additions_mut(&mut self) -> Vec<$crate::settings::Addition<'_>> {
                #[allow(unused_mut)]
                let mut list = Vec::new();
                $(
                    settings_group!(
                        @addition list, stringify!($field), concat!($($doc, "\n",)*), self.$field, $paper
                    );
                )*
                list
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

/// A setting that is an on/off switch (an addition of ours when the paper's mode sets it).
pub trait AsToggle {
    fn as_toggle(&mut self) -> Option<&mut bool> {
        None
    }
}

impl AsToggle for bool {
    fn as_toggle(&mut self) -> Option<&mut bool> {
        Some(self)
    }
}

impl AsToggle for u32 {}
impl AsToggle for f32 {}
impl AsToggle for Mode {}

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

    /// Checks ranges; the message names the setting.
    pub fn validate(&self) -> Result<(), String> {
        self.map.validate()?;
        self.filter.validate()?;
        self.display.validate()?;
        self.light.validate()
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

/// A number that must be finite and positive, else an error naming it.
pub(crate) fn positive(name: &str, v: f32) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{name} must be a positive number, got {v}"))
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
}
