//! Where two settings records (JSON) first differ: what tells a resumed, replayed or rechecked
//! run's settings from its record's, and runs pooled in one acceptance table apart.

/// Where two settings records first differ: the dotted key and both values.
#[derive(Clone, Debug, PartialEq)]
pub struct Difference {
    /// Dotted key, indexed in arrays, e.g. `optimiser.length` (`(root)` for two scalars).
    pub key: String,
    /// The value in the record (`a`), as JSON, or `absent`.
    pub recorded: String,
    /// The value now (`b`).
    pub now: String,
}

impl Difference {
    /// `"; a --quick run {is_read} with --quick"` when the difference is in the one setting a
    /// `--quick` run changes (its optimiser budget), else nothing: the likely cause, named.
    pub fn quick_hint(&self, is_read: &str) -> String {
        match self.key.as_str() {
            "optimiser.length" | "opt_length" => format!("; a --quick run {is_read} with --quick"),
            _ => String::new(),
        }
    }
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "`{}` differs (recorded {}, now {})",
            self.key, self.recorded, self.now
        )
    }
}

/// The first key at which two JSON values differ, with both values there; `at` is the key
/// prefix of `a` and `b` (empty at the top). Object keys are visited in sorted order.
pub fn first_difference(
    a: &serde_json::Value,
    b: &serde_json::Value,
    at: String,
) -> Option<Difference> {
    use serde_json::Value::{Array, Object};
    let shown = |v: Option<&serde_json::Value>| {
        let text = v.map_or_else(|| "absent".to_string(), |v| v.to_string());
        match text.char_indices().nth(60) {
            Some((cut, _)) => format!("{}…", &text[..cut]),
            None => text,
        }
    };
    match (a, b) {
        (Object(x), Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter().find_map(|k| {
                let path = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                match (x.get(k), y.get(k)) {
                    (Some(u), Some(v)) => first_difference(u, v, path),
                    (u, v) => Some(Difference {
                        key: path,
                        recorded: shown(u),
                        now: shown(v),
                    }),
                }
            })
        }
        (Array(x), Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (u, v))| first_difference(u, v, format!("{at}[{i}]"))),
        _ if a == b => None,
        _ => Some(Difference {
            key: if at.is_empty() { "(root)".into() } else { at },
            recorded: shown(Some(a)),
            now: shown(Some(b)),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn the_first_differing_key_is_named_with_both_values() {
        let a = json!({"gp": {"floor": [1.0, 2.0]}, "optimiser": {"length": 50}});
        assert_eq!(first_difference(&a, &a.clone(), String::new()), None);

        let mut b = a.clone();
        b["gp"]["floor"][1] = json!(3.0);
        b["optimiser"]["length"] = json!(5);
        let d = first_difference(&a, &b, String::new()).unwrap();
        assert_eq!(d.key, "gp.floor[1]", "sorted keys: gp before optimiser");
        assert_eq!(
            d.to_string(),
            "`gp.floor[1]` differs (recorded 2.0, now 3.0)"
        );
        assert_eq!(d.quick_hint("resumes"), "");

        b["gp"] = a["gp"].clone();
        let d = first_difference(&a, &b, String::new()).unwrap();
        assert_eq!(
            d.quick_hint("resumes"),
            "; a --quick run resumes with --quick"
        );

        let d = first_difference(&json!({}), &json!({"sensor_noise": false}), String::new());
        assert_eq!(
            d.unwrap().to_string(),
            "`sensor_noise` differs (recorded absent, now false)"
        );
        let long = json!("x".repeat(100));
        let d = first_difference(&long, &json!(1), String::new()).unwrap();
        assert_eq!(d.key, "(root)");
        assert!(d.recorded.ends_with('…') && d.recorded.chars().count() == 61);
    }
}
