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
    /// The one setting a `--quick` run changes, so the hint to add `--quick` applies.
    pub fn is_quick_budget(&self) -> bool {
        matches!(self.key.as_str(), "optimiser.length" | "opt_length")
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
