//! The `config` block of an arm run's `summary.json`: the run's settings, plus keys derived from
//! them (the scene, the keys marked ours, the start interval, the simulator's own config) or
//! about the machine (the floating-point mode) so that the report and readers of the summary
//! need not rebuild them. [`arm_settings`] takes those keys off again, which is how `recheck`
//! learns a recorded run's settings; both directions live here so the list cannot drift.

use crate::config::ArmExperiment;
use crate::{arm, subnormals, ExperimentError};
use serde_json::{json, Value};

/// Keys [`arm_summary_config`] adds beside the settings (not part of an [`ArmExperiment`]).
pub const DERIVED_CONFIG_KEYS: [&str; 5] = [
    "geometry",
    "ours",
    "start_y_range",
    "simulator",
    "subnormals",
];

/// The `config` block an arm run's summary records for the settings `cfg`.
pub fn arm_summary_config(cfg: &ArmExperiment) -> Result<Value, ExperimentError> {
    let arm_cfg = arm::arm_config(cfg);
    let g = &arm_cfg.geometry;
    let mut config = serde_json::to_value(cfg).map_err(|e| ExperimentError::Write(e.into()))?;
    config["geometry"] = json!({
        "wall_x": g.wall_x(),
        "hole_y": g.hole_center[1],
        "hole_r": g.hole_radius,
        "end_x": g.end_x(),
        "spring_catch_x": g.spring_catch_x(),
    });
    config["ours"] = json!(cfg.ours_keys());
    if let Some(r) = cfg.start.y_range {
        config["start_y_range"] = json!(r);
    }
    config["simulator"] =
        serde_json::to_value(&arm_cfg).map_err(|e| ExperimentError::Write(e.into()))?;
    // Runs before the flushing (and runs whose rayon pool could not flush) used gradual
    // underflow; their numbers differ below 1e-300 and their optimiser paths may part. This is
    // the latest session's mode; `sessions` lists each session's.
    config["subnormals"] = json!(subnormals::mode_here());
    Ok(config)
}

/// The settings a summary's `config` block records: it without [`DERIVED_CONFIG_KEYS`].
pub fn arm_settings(config: &Value) -> Result<ArmExperiment, serde_json::Error> {
    let mut settings = config.clone();
    if let Some(map) = settings.as_object_mut() {
        for key in DERIVED_CONFIG_KEYS {
            map.remove(key);
        }
    }
    serde_json::from_value(settings)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{parse, shipped, CONFIGS};
    use std::collections::BTreeSet;

    #[test]
    fn every_shipped_config_round_trips_and_every_derived_key_is_one_it_adds() {
        let mut added_somewhere = BTreeSet::new();
        for (name, _) in CONFIGS {
            let (label, text) = shipped(name).expect("a shipped name");
            let cfg = parse(text, label).expect("shipped configs parse");
            let settings = serde_json::to_value(&cfg).unwrap();
            let recorded = arm_summary_config(&cfg).unwrap();
            let added: BTreeSet<&str> = recorded
                .as_object()
                .unwrap()
                .keys()
                .filter(|k| !settings.as_object().unwrap().contains_key(*k))
                .map(String::as_str)
                .collect();
            for key in &added {
                assert!(
                    DERIVED_CONFIG_KEYS.contains(key),
                    "{name}: `{key}` is added to the summary's config but not listed"
                );
            }
            added_somewhere.extend(added.iter().map(|k| k.to_string()));
            let back = serde_json::to_value(arm_settings(&recorded).unwrap()).unwrap();
            assert_eq!(back, settings, "{name}: settings lost in the round trip");
        }
        let listed: BTreeSet<String> = DERIVED_CONFIG_KEYS.iter().map(|k| k.to_string()).collect();
        assert_eq!(
            added_somewhere, listed,
            "a listed key no shipped config's summary has"
        );
    }
}
