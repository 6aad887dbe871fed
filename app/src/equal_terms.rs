//! Whether a comparison is on equal terms: the per-light map resolution of each side.
//!
//! Techniques have their own default map resolutions (the reference 1024², INSM 512², the per-VPL maps 128²,
//! the VALs 256²), so `compare` or `sweep` without `--shadow-res` compares two resolutions unless told. That
//! can be what a user wants (a VAL map against per-VPL maps of another size), never what they should not
//! see: the CLI says so, and the sweep's CSV names each side's resolution.

use std::collections::BTreeMap;

/// The parameters (from [`crate::measure::Rendered::parameters`]) that hold a side's map resolutions: the
/// direct technique's, then the indirect technique's.
const RESOLUTION_KEYS: [(&str, &str); 2] = [("shadow_res", "maps"), ("indirect.shadow_res", "indirect maps")];

/// A side's map resolutions, one per key of [`RESOLUTION_KEYS`] (empty where the side has no such maps).
pub fn resolutions(parameters: &BTreeMap<String, String>) -> [String; 2] {
    RESOLUTION_KEYS.map(|(key, _)| parameters.get(key).cloned().unwrap_or_default())
}

/// A note when both sides have maps of one kind at different resolutions, naming both; `None` on equal terms.
pub fn resolution_note(
    technique: &str,
    parameters: &BTreeMap<String, String>,
    against: &str,
    against_parameters: &BTreeMap<String, String>,
) -> Option<String> {
    let differing: Vec<String> = RESOLUTION_KEYS
        .iter()
        .filter_map(|(key, what)| {
            let (a, b) = (parameters.get(*key)?, against_parameters.get(*key)?);
            (a != b).then(|| format!("{what} {technique} {a}², {against} {b}²"))
        })
        .collect();
    (!differing.is_empty()).then(|| {
        format!(
            "not at one resolution: {} (techniques have their own defaults: --shadow-res N sets both direct \
             sides, --param/--against-param shadow_res=N one, --indirect-param/--against-indirect-param \
             shadow_res=N the indirect ones)",
            differing.join(", and ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    #[test]
    fn a_note_names_both_resolutions_only_when_they_differ() {
        let insm = params(&[("shadow_res", "512"), ("k", "10")]);
        let reference = params(&[("shadow_res", "1024")]);
        let note = resolution_note("insm", &insm, "reference", &reference).expect("512 against 1024");
        assert!(note.contains("insm 512²") && note.contains("reference 1024²"), "{note}");
        assert!(resolution_note("insm", &insm, "reference", &params(&[("shadow_res", "512")])).is_none());
        // A side without maps (the ray tracer) is no mismatch.
        assert!(resolution_note("insm", &insm, "raytraced", &params(&[("samples", "1")])).is_none());
        // The indirect technique's maps are compared apart from the direct one's.
        let val = params(&[("indirect.shadow_res", "128")]);
        let per_vpl = params(&[("indirect.shadow_res", "256")]);
        let note = resolution_note("val", &val, "vpl-shadowmaps", &per_vpl).expect("128 against 256");
        assert!(note.contains("indirect maps val 128², vpl-shadowmaps 256²"), "{note}");
        assert_eq!(note.matches('²').count(), 2, "only the indirect maps differ: {note}");
        // Both kinds differing are both named.
        let both = resolution_note(
            "a",
            &params(&[("shadow_res", "512"), ("indirect.shadow_res", "128")]),
            "b",
            &params(&[("shadow_res", "1024"), ("indirect.shadow_res", "256")]),
        )
        .unwrap();
        assert!(both.contains("maps a 512², b 1024², and indirect maps a 128², b 256²"), "{both}");
        assert_eq!(resolutions(&insm), ["512".to_string(), String::new()]);
        assert_eq!(resolutions(&val), [String::new(), "128".to_string()]);
    }
}
