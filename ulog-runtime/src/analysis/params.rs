//! Parameters whose value is not the log's default: each initial parameter against its
//! default parameter (`Q`: the system default, else the configuration's).

use super::{Missing, NonDefault};
use crate::read::{DefaultParameter, Metadata};

/// Every initial parameter that differs from its default, by name.
pub(super) fn non_default(meta: &Metadata, missing: &mut Vec<Missing>) -> Vec<NonDefault> {
    let defaults = meta.default_parameters();
    if defaults.is_empty() {
        missing.push(Missing {
            fact: "non_default_params".to_owned(),
            reason: "the log has no default parameters".to_owned(),
        });
        return Vec::new();
    }
    let default = |name: &str| -> Option<f64> {
        let of = |bit: u8| {
            defaults
                .iter()
                .rev()
                .find(|d: &&DefaultParameter| d.name == name && d.default_types & bit != 0)
                .map(|d| d.value.as_f64())
        };
        of(DefaultParameter::SYSTEM).or_else(|| of(DefaultParameter::CONFIGURATION))
    };
    let mut out: Vec<NonDefault> = meta
        .initial_parameters()
        .iter()
        .filter_map(|p| {
            let d = default(&p.name)?;
            let v = p.value.as_f64();
            (v != d && !(v.is_nan() && d.is_nan())).then(|| NonDefault {
                name: p.name.clone(),
                value: v,
                default: d,
            })
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}
