//! The plugin's saved state (the JSON a host stores in its project and hands back when the
//! project is opened) made safe before nice-plug applies it.
//!
//! nice-plug restores each value as it was written, unclamped: a float parameter takes any
//! `f32` (a state written by hand, by another version or damaged on disk may hold 1e30 mm or
//! infinity), an enum any variant index. [`sanitize`], called by the wrapper through
//! `Plugin::filter_state` just before the values are applied, clamps every float into its
//! parameter's range, drops values that are not finite, enum indices past the last variant and
//! keys no parameter has, so that the engine only ever sees settings inside their ranges. A value
//! that is dropped keeps the parameter's current value, as nice-plug does for a value of the
//! wrong type.
//!
//! [`restore`] is the wrapper's whole load path (`deserialize_json` and `deserialize_object` in
//! nice-plug's `wrapper/state.rs`, which are private to that crate) written out against the
//! public API, so that tests and the `plugin_state` fuzz target can run it without a host.

use crate::params::JavariParams;
use nice_plug::params::internals::ParamPtr;
use nice_plug::params::range::FloatRange;
use nice_plug::params::{InternalParamMut, Param, Params};
use nice_plug::plugin::{ParamValue, PluginState};
use std::collections::BTreeMap;

/// The inclusive bounds of a float parameter's range, lowest first.
fn float_range_bounds(range: &FloatRange) -> (f32, f32) {
    match range {
        FloatRange::Linear { min, max }
        | FloatRange::Skewed { min, max, .. }
        | FloatRange::SymmetricalSkewed { min, max, .. } => (min.min(*max), max.max(*min)),
        FloatRange::Reversed(inner) => float_range_bounds(inner),
    }
}

/// Clamps or drops every value of `state` so that applying it leaves each parameter inside its
/// range (see the module doc).
pub fn sanitize(state: &mut PluginState) {
    let params = JavariParams::default();
    let param_map = params.param_map();
    state.params.retain(|id, value| {
        let Some((_, pointer, _)) = param_map.iter().find(|(param_id, _, _)| param_id == id) else {
            return false;
        };
        match (pointer, value) {
            (ParamPtr::FloatParam(param), ParamValue::F32(plain)) => {
                // SAFETY: `param_map` points into `params`, which lives until this function
                // returns.
                let range = unsafe { (**param).range() };
                let (min, max) = float_range_bounds(&range);
                if !plain.is_finite() {
                    return false;
                }
                *plain = plain.clamp(min, max);
                true
            }
            (ParamPtr::EnumParam(param), ParamValue::I32(index)) => {
                // SAFETY: as above.
                let variants = unsafe { (**param).step_count() }.map_or(1, |steps| steps + 1);
                usize::try_from(*index).is_ok_and(|index| index < variants)
            }
            (ParamPtr::IntParam(_), ParamValue::I32(_)) => false,
            // Bools, enum IDs (matched against the variants' IDs by nice-plug) and values of the
            // wrong type (ignored by nice-plug) pass through unchanged.
            _ => true,
        }
    });
}

/// Parses saved state bytes and applies them to `params` as nice-plug's wrapper does on a
/// host's state load (see the module doc). The error says why the bytes are not a state.
pub fn restore(params: &JavariParams, bytes: &[u8]) -> Result<(), String> {
    let mut state: PluginState = serde_json::from_slice(bytes)
        .map_err(|error| format!("not a saved Javari state: {error}"))?;
    sanitize(&mut state);
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
/// panics for an index past the last variant; [`sanitize`] keeps such indices out.
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

    fn state_with(params: &str) -> Vec<u8> {
        format!("{{\"version\":\"0.1.0\",\"params\":{{{params}}},\"fields\":{{}}}}").into_bytes()
    }

    #[test]
    fn values_outside_their_ranges_are_clamped_or_dropped() {
        let params = JavariParams::default();
        let bytes = state_with(
            "\"thpos\":{\"f32\":1e30},\"gamma\":{\"f32\":-5.0},\"eta\":{\"f32\":1e39},\
             \"preset\":{\"i32\":99},\"inst\":{\"i32\":-1},\"nokey\":{\"f32\":1.0},\
             \"dbpm\":{\"f32\":72.5}",
        );
        restore(&params, &bytes).unwrap();
        assert_eq!(params.thread_position_mm.value(), 45.0);
        assert_eq!(params.gamma_per_s.value(), 0.0);
        // 1e39 is infinity as an f32: dropped, the default stays.
        assert_eq!(params.eta_ns.value(), 7.0);
        assert_eq!(params.preset.value(), crate::params::PresetChoice::Custom);
        assert_eq!(params.drone_tempo_bpm.value(), 72.5);
        assert!(parameters_out_of_range(&params).is_empty());
    }

    #[test]
    fn without_sanitizing_the_same_state_leaves_ranges() {
        // The check above is needed: nice-plug alone stores the value as written.
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
        let bytes = state_with(
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

    #[test]
    fn bytes_that_are_not_a_state_are_an_error() {
        let error = restore(&JavariParams::default(), b"\x28\xb5\x2f\xfd garbage").unwrap_err();
        assert!(error.starts_with("not a saved Javari state"), "{error}");
    }
}
