//! A host's state blob made safe before nice-plug applies it ([`repair`], called from
//! `Plugin::filter_state`).
//!
//! nice-plug stores the parameters as JSON by their stable IDs (plain values: `f32` numbers,
//! booleans, enum IDs). It applies whatever a blob that parses holds, without range checks, and
//! leaves a parameter the blob lacks at its *current* value. So a state from another plugin (or
//! another program's JSON) would keep whatever was set, and an edited or damaged one could put
//! k_b at 10^39 or the gain at +∞, which the parameter would then also save back (as a JSON
//! `null` that no longer loads). Here:
//!
//! - a blob holding none of Javari's IDs is foreign: every parameter takes its default;
//! - an ID the blob lacks, or holds with the wrong kind of value (a number for a switch, an
//!   unknown enum ID), takes its default;
//! - a number outside its parameter's range is clamped to the range (±∞ to the nearer end);
//! - IDs Javari does not know are dropped;
//! - an enum ID of a choice Javari has withdrawn is migrated to the choice that took its place:
//!   `qual = "draft"` (the draft tier, withdrawn in stop 62) loads as `"live"`
//!   (`Quality::withdrawn`).
//!
//! Each repair is logged (`nice_warn!`) and returned, so that it is said, not silent.
//!
//! [`restore`] is the wrapper's whole load path (`deserialize_json` and `deserialize_object` in
//! nice-plug's `wrapper/state.rs`, which are private to that crate) written out against the
//! public API, with [`save`] its save path, so that tests and the `plugin_state` fuzz target can
//! run them without a host.
//!
//! Bytes that are not a nice-plug state at all (not JSON, or JSON of another shape) never reach
//! this function: nice-plug refuses them, tells the host that the load failed (CLAP `false`,
//! VST3 `kResultFalse`) and changes no parameter, so the instance keeps the values it had,
//! its defaults when the host has just created it. The host tests feed such blobs too.

use crate::params::JavariParams;
use javari_core::tanpura::quality::Quality;
use nice_plug::params::internals::ParamPtr;
use nice_plug::params::InternalParamMut;
use nice_plug::plugin::ParamValue;
use nice_plug::prelude::*;
use std::collections::BTreeMap;

/// The quality parameter's ID; its enum IDs are the core's tier names.
const QUALITY_ID: &str = "qual";

/// What [`repair`] changed in a state.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateRepairs {
    /// The blob held none of Javari's parameter IDs: every parameter took its default.
    pub foreign: bool,
    /// IDs that were missing or held the wrong kind of value, now at their defaults.
    pub defaulted: Vec<String>,
    /// IDs whose number lay outside the parameter's range, now clamped.
    pub clamped: Vec<String>,
    /// IDs Javari does not know, dropped.
    pub dropped: Vec<String>,
    /// IDs whose value named a withdrawn choice, now the choice that replaced it.
    pub migrated: Vec<String>,
}

impl StateRepairs {
    /// True when the state was applied as it came.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// The state value one parameter takes by default, in nice-plug's serialised form.
///
/// # Safety
/// `param` must point into a live `Params` object.
unsafe fn default_value(param: ParamPtr) -> ParamValue {
    unsafe {
        match param {
            ParamPtr::FloatParam(p) => ParamValue::F32((*p).default_plain_value()),
            ParamPtr::IntParam(p) => ParamValue::I32((*p).default_plain_value()),
            ParamPtr::BoolParam(p) => ParamValue::Bool((*p).default_plain_value()),
            ParamPtr::EnumParam(p) => {
                // Back to the default (an enum check may have moved it), then read its ID.
                param._internal_set_normalized_value(param.default_normalized_value());
                match (*p).unmodulated_plain_id() {
                    Some(id) => ParamValue::String(id.to_owned()),
                    None => ParamValue::I32((*p).default_plain_value()),
                }
            }
        }
    }
}

/// The lowest and highest plain value of a float range.
fn float_bounds(range: FloatRange) -> (f32, f32) {
    let (a, b) = (range.unnormalize(0.0), range.unnormalize(1.0));
    (a.min(b), a.max(b))
}

enum Check {
    Valid,
    Clamped(ParamValue),
    WrongKind,
}

/// Whether `value` suits `param` (an enum ID is tried on `param`, which must be a scratch
/// instance's).
///
/// # Safety
/// `param` must point into a live `Params` object.
unsafe fn check(param: ParamPtr, value: &ParamValue) -> Check {
    unsafe {
        match (param, value) {
            (ParamPtr::FloatParam(p), ParamValue::F32(number)) => {
                let (min, max) = float_bounds((*p).range());
                if number.is_nan() {
                    Check::WrongKind
                } else if *number < min || *number > max {
                    Check::Clamped(ParamValue::F32(number.clamp(min, max)))
                } else {
                    Check::Valid
                }
            }
            (ParamPtr::IntParam(p), ParamValue::I32(number)) => {
                let (a, b) = ((*p).preview_plain(0.0), (*p).preview_plain(1.0));
                let (min, max) = (a.min(b), a.max(b));
                if (min..=max).contains(number) {
                    Check::Valid
                } else {
                    Check::Clamped(ParamValue::I32((*number).clamp(min, max)))
                }
            }
            (ParamPtr::BoolParam(_), ParamValue::Bool(_)) => Check::Valid,
            (ParamPtr::EnumParam(p), ParamValue::String(id)) => {
                if (*p).set_from_id(id) {
                    Check::Valid
                } else {
                    Check::WrongKind
                }
            }
            (ParamPtr::EnumParam(p), ParamValue::I32(index)) => {
                if (0..(*p).len() as i32).contains(index) {
                    Check::Valid
                } else {
                    Check::WrongKind
                }
            }
            _ => Check::WrongKind,
        }
    }
}

/// Repairs `state` in place (see the module doc) and logs what it changed.
pub fn repair(state: &mut PluginState) -> StateRepairs {
    // A scratch set of parameters: its ranges, defaults and enum IDs. Enum checks move its
    // values; the plugin's own parameters are untouched here.
    let scratch = JavariParams::default();
    let params = scratch.param_map();
    let mut repairs = StateRepairs::default();

    let known = |id: &str| params.iter().any(|(known, _, _)| known == id);
    repairs.dropped = state
        .params
        .keys()
        .filter(|id| !known(id))
        .cloned()
        .collect();
    for id in &repairs.dropped {
        state.params.remove(id);
    }
    repairs.foreign = state.params.is_empty();
    if let Some(ParamValue::String(tier)) = state.params.get_mut(QUALITY_ID) {
        if let Some(quality) = Quality::withdrawn(tier) {
            *tier = quality.name().to_owned();
            repairs.migrated.push(QUALITY_ID.to_owned());
        }
    }

    for (id, param, _) in &params {
        // SAFETY: `param` points into `scratch`, alive until the end of this function.
        let repaired = match state.params.get(id) {
            None => None,
            Some(value) => match unsafe { check(*param, value) } {
                Check::Valid => continue,
                Check::Clamped(value) => {
                    repairs.clamped.push(id.clone());
                    Some(value)
                }
                Check::WrongKind => None,
            },
        };
        let value = match repaired {
            Some(value) => value,
            None => {
                if !repairs.foreign {
                    repairs.defaulted.push(id.clone());
                }
                // SAFETY: as above.
                unsafe { default_value(*param) }
            }
        };
        state.params.insert(id.clone(), value);
    }

    if repairs.foreign {
        nice_warn!(
            "Javari: the state holds none of Javari's parameters (another plugin's, or damaged); \
             loading the defaults"
        );
    } else if !repairs.is_empty() {
        nice_warn!(
            "Javari: state repaired: defaults for {:?} (missing or of the wrong kind), clamped \
             to range {:?}, unknown IDs dropped {:?}, withdrawn choices migrated {:?}",
            repairs.defaulted,
            repairs.clamped,
            repairs.dropped,
            repairs.migrated
        );
    }
    repairs
}

/// The inclusive bounds of a float parameter's range, lowest first.
fn float_range_bounds(range: &FloatRange) -> (f32, f32) {
    match range {
        FloatRange::Linear { min, max }
        | FloatRange::Skewed { min, max, .. }
        | FloatRange::SymmetricalSkewed { min, max, .. } => (min.min(*max), max.max(*min)),
        FloatRange::Reversed(inner) => float_range_bounds(inner),
    }
}

/// Parses saved state bytes and applies them to `params` as nice-plug's wrapper does on a
/// host's state load (see the module doc). The error says why the bytes are not a state.
pub fn restore(params: &JavariParams, bytes: &[u8]) -> Result<(), String> {
    let mut state: PluginState = serde_json::from_slice(bytes)
        .map_err(|error| format!("not a saved Javari state: {error}"))?;
    repair(&mut state);
    let param_map = params.param_map();
    for (id, value) in &state.params {
        let Some((_, pointer, _)) = param_map.iter().find(|(param_id, _, _)| param_id == id) else {
            continue;
        };
        // SAFETY: `param_map` points into `params`, which outlives this loop; nice-plug's wrapper
        // makes the same calls on the same pointers.
        unsafe {
            match (pointer, value) {
                (ParamPtr::FloatParam(param), ParamValue::F32(plain)) => {
                    (**param)._internal_set_plain_value(*plain);
                }
                (ParamPtr::IntParam(param), ParamValue::I32(plain)) => {
                    (**param)._internal_set_plain_value(*plain);
                }
                (ParamPtr::BoolParam(param), ParamValue::Bool(plain)) => {
                    (**param)._internal_set_plain_value(*plain);
                }
                (ParamPtr::EnumParam(param), ParamValue::I32(index)) => {
                    (**param)._internal_set_plain_value(*index);
                }
                (ParamPtr::EnumParam(param), ParamValue::String(variant_id)) => {
                    (**param).set_from_id(variant_id);
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// The parameters as nice-plug's wrapper saves them (`serialize_object`): floats, bools and
/// enum variant IDs by parameter ID. Saving reads each enum's variant ID by its index, which
/// panics for an index past the last variant; [`repair`] keeps such indices out.
pub fn save(params: &JavariParams) -> PluginState {
    let mut saved = BTreeMap::new();
    for (id, pointer, _) in params.param_map() {
        // SAFETY: `param_map` points into `params`, which outlives this loop.
        let value = unsafe {
            match pointer {
                ParamPtr::FloatParam(param) => ParamValue::F32((*param).unmodulated_plain_value()),
                ParamPtr::IntParam(param) => ParamValue::I32((*param).unmodulated_plain_value()),
                ParamPtr::BoolParam(param) => ParamValue::Bool((*param).unmodulated_plain_value()),
                ParamPtr::EnumParam(param) => match (*param).unmodulated_plain_id() {
                    Some(variant_id) => ParamValue::String(variant_id.to_string()),
                    None => ParamValue::I32((*param).unmodulated_plain_value()),
                },
            }
        };
        saved.insert(id, value);
    }
    PluginState {
        version: env!("CARGO_PKG_VERSION").to_string(),
        params: saved,
        fields: params.serialize_fields(),
    }
}

/// Every parameter whose value lies outside its range: (ID, value), empty when all are inside.
pub fn parameters_out_of_range(params: &JavariParams) -> Vec<(String, f32)> {
    let mut outside = Vec::new();
    for (id, pointer, _) in params.param_map() {
        // SAFETY: `param_map` points into `params`, which outlives this loop.
        unsafe {
            match pointer {
                ParamPtr::FloatParam(param) => {
                    let (min, max) = float_range_bounds(&(*param).range());
                    let value = (*param).value();
                    // `!(a <= b)` so that a NaN counts as outside.
                    if !(min <= value && value <= max) {
                        outside.push((id, value));
                    }
                }
                ParamPtr::EnumParam(param) => {
                    let variants = (*param).step_count().map_or(1, |steps| steps + 1);
                    let index = pointer.unmodulated_plain_value();
                    if !(0.0 <= index && index < variants as f32) {
                        outside.push((id, index));
                    }
                }
                _ => {}
            }
        }
    }
    outside
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// The state a fresh instance saves: every parameter at its default.
    fn default_state() -> PluginState {
        let mut state = PluginState {
            version: String::new(),
            params: BTreeMap::new(),
            fields: BTreeMap::new(),
        };
        repair(&mut state);
        state
    }

    /// `ParamValue` has no `PartialEq`: compare through its `Debug` text.
    fn text<T: std::fmt::Debug>(value: &T) -> String {
        format!("{value:?}")
    }

    fn state_with(params: &[(&str, ParamValue)]) -> PluginState {
        PluginState {
            version: "0.1.0".to_string(),
            params: params
                .iter()
                .map(|(id, value)| (id.to_string(), value.clone()))
                .collect(),
            fields: BTreeMap::new(),
        }
    }

    #[test]
    fn a_foreign_state_loads_every_default() {
        let mut state = state_with(&[
            ("cutoff", ParamValue::F32(1000.0)),
            ("resonance", ParamValue::Bool(true)),
        ]);
        let repairs = repair(&mut state);
        assert!(repairs.foreign);
        assert_eq!(repairs.dropped, ["cutoff", "resonance"]);
        assert_eq!(text(&state.params), text(&default_state().params));
        assert_eq!(
            state.params.len(),
            JavariParams::default().param_map().len()
        );
        assert_eq!(text(&state.params["gain"]), "F32(0.0)");
        assert_eq!(text(&state.params["qual"]), r#"String("fine")"#);
    }

    #[test]
    fn wrong_kinds_and_missing_ids_take_defaults_and_numbers_are_clamped() {
        let mut state = state_with(&[
            ("gain", ParamValue::F32(f32::INFINITY)),
            ("kb", ParamValue::F32(39.0)),
            ("thpos", ParamValue::F32(-1e30)),
            ("gamma", ParamValue::F32(0.25)),
            ("thon", ParamValue::F32(1.0)),
            ("qual", ParamValue::String("ultra".to_string())),
            ("inst", ParamValue::I32(7)),
            ("first", ParamValue::String("ma".to_string())),
        ]);
        let repairs = repair(&mut state);
        assert!(!repairs.foreign);
        assert_eq!(
            repairs.clamped,
            ["thpos", "kb", "gain"],
            "in parameter order"
        );
        assert_eq!(text(&state.params["gain"]), "F32(24.0)");
        assert_eq!(text(&state.params["kb"]), "F32(11.0)");
        assert_eq!(text(&state.params["thpos"]), "F32(30.0)");
        assert_eq!(text(&state.params["gamma"]), "F32(0.25)", "kept");
        assert_eq!(text(&state.params["first"]), r#"String("ma")"#, "kept");
        for id in ["thon", "qual", "inst", "drone", "plamp"] {
            assert!(repairs.defaulted.iter().any(|d| d == id), "{id}");
            let default = default_state();
            assert_eq!(text(&state.params[id]), text(&default.params[id]), "{id}");
        }
    }

    #[test]
    fn a_valid_state_passes_unchanged() {
        let mut state = default_state();
        state
            .params
            .insert("gain".to_string(), ParamValue::F32(-6.0206));
        let before = text(&state.params);
        assert!(repair(&mut state).is_empty());
        assert_eq!(text(&state.params), before);
    }

    // The wrapper's load path written out ([`restore`]), as the fuzz target runs it.
    fn state_bytes(params: &str) -> Vec<u8> {
        format!("{{\"version\":\"0.1.0\",\"params\":{{{params}}},\"fields\":{{}}}}").into_bytes()
    }

    #[test]
    fn values_outside_their_ranges_are_clamped_or_dropped() {
        let params = JavariParams::default();
        let bytes = state_bytes(
            "\"thpos\":{\"f32\":1e30},\"gamma\":{\"f32\":-5.0},\"eta\":{\"f32\":1e39},\
             \"preset\":{\"i32\":99},\"inst\":{\"i32\":-1},\"nokey\":{\"f32\":1.0},\
             \"dbpm\":{\"f32\":72.5}",
        );
        restore(&params, &bytes).unwrap();
        assert_eq!(params.thread_position_mm.value(), 45.0);
        assert_eq!(params.gamma_per_s.value(), 0.0);
        // 1e39 is infinity as an f32: clamped to the range's end.
        assert_eq!(params.eta_ns.value(), 1000.0);
        assert_eq!(params.preset.value(), crate::params::PresetChoice::Custom);
        assert_eq!(params.drone_tempo_bpm.value(), 72.5);
        assert!(parameters_out_of_range(&params).is_empty());
    }

    #[test]
    fn without_repairing_the_same_state_leaves_ranges() {
        // The repair above is needed: nice-plug alone stores the value as written.
        let params = JavariParams::default();
        unsafe { params.thread_position_mm._internal_set_plain_value(1e30) };
        assert_eq!(
            parameters_out_of_range(&params),
            vec![("thpos".to_string(), 1e30)]
        );
    }

    #[test]
    fn enum_ids_and_in_range_values_load_unchanged() {
        let params = JavariParams::default();
        let bytes = state_bytes(
            "\"inst\":{\"string\":\"bowed\"},\"thon\":{\"bool\":false},\"kb\":{\"f32\":9.25}",
        );
        restore(&params, &bytes).unwrap();
        assert_eq!(
            params.instrument.value(),
            crate::params::InstrumentChoice::Bowed
        );
        assert!(!params.thread_enabled.value());
        assert_eq!(params.bridge_stiffness_log10.value(), 9.25);
    }

    /// A state saved while the draft tier existed loads with the live tier, said as a repair; the
    /// plugin's quality IDs are the core's tier names, which the migration relies on.
    #[test]
    fn a_state_with_the_withdrawn_draft_tier_loads_as_live() {
        let mut state = default_state();
        state.params.insert(
            QUALITY_ID.to_string(),
            ParamValue::String("draft".to_string()),
        );
        let repairs = repair(&mut state);
        assert_eq!(repairs.migrated, [QUALITY_ID]);
        assert!(repairs.defaulted.is_empty(), "{repairs:?}");
        assert_eq!(text(&state.params[QUALITY_ID]), r#"String("live")"#);

        let params = JavariParams::default();
        restore(&params, &state_bytes("\"qual\":{\"string\":\"draft\"}")).unwrap();
        assert_eq!(params.quality.value(), crate::params::QualityChoice::Live);
        for quality in Quality::ALL {
            let params = JavariParams::default();
            let bytes = state_bytes(&format!("\"qual\":{{\"string\":\"{}\"}}", quality.name()));
            restore(&params, &bytes).unwrap();
            assert_eq!(
                params.quality.value().quality(),
                quality,
                "{}",
                quality.name()
            );
        }
    }

    #[test]
    fn bytes_that_are_not_a_state_are_an_error() {
        let error = restore(&JavariParams::default(), b"\x28\xb5\x2f\xfd garbage").unwrap_err();
        assert!(error.starts_with("not a saved Javari state"), "{error}");
    }
}
