//! Every key a config accepts is documented where a user looks: set (with its comment) in a
//! shipped file, or listed in the README's table of the keys the shipped files leave out.

use std::collections::BTreeSet;
use vicpilco_experiments::config::{self, CONFIGS};

const PROBE: &str = "zz_not_a_key";

/// The keys `table` accepts ("" is the top level), read from the parser's own refusal of an
/// unknown one (serde lists every field it expected), so a new field cannot be missed; `None`
/// when `table` is not a table (the probe fails otherwise: a type error, a duplicate key).
fn accepted_keys(table: &str) -> Option<Vec<String>> {
    let (_, base) = config::shipped("vilta").unwrap();
    let text = match table {
        "" => format!("{PROBE} = 1\n{base}"),
        t if base.contains(&format!("\n[{t}]\n")) => {
            base.replace(&format!("\n[{t}]\n"), &format!("\n[{t}]\n{PROBE} = 1\n"))
        }
        t => format!("{base}\n[{t}]\n{PROBE} = 1\n"),
    };
    let e = config::parse(&text, "probe.toml").unwrap_err().to_string();
    if !e.contains(&format!("unknown field `{PROBE}`")) {
        return None;
    }
    let list = e
        .split_once("expected one of ")
        .or_else(|| e.split_once("expected "))
        .unwrap_or_else(|| panic!("[{table}]: no list of expected keys in {e}"))
        .1;
    let keys: Vec<String> = list
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|k| {
            if table.is_empty() {
                k.to_string()
            } else {
                format!("{table}.{k}")
            }
        })
        .collect();
    assert!(!keys.is_empty(), "[{table}]: {e}");
    Some(keys)
}

/// Every table of an arm config, found by probing each accepted key as one, and every key.
fn tables_and_keys() -> (BTreeSet<String>, BTreeSet<String>) {
    let (mut tables, mut keys) = (BTreeSet::new(), BTreeSet::new());
    let mut pending = vec![String::new()];
    while let Some(table) = pending.pop() {
        let Some(found) = accepted_keys(&table) else {
            continue;
        };
        tables.insert(table);
        for k in found {
            if keys.insert(k.clone()) {
                pending.push(k);
            }
        }
    }
    (tables, keys)
}

/// Dotted keys set in some shipped file.
fn shipped_keys() -> BTreeSet<String> {
    fn walk(prefix: &str, v: &toml::Value, out: &mut BTreeSet<String>) {
        if let toml::Value::Table(t) = v {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                walk(&key, v, out);
                out.insert(key);
            }
        }
    }
    let mut out = BTreeSet::new();
    for (_, text) in CONFIGS {
        walk("", &toml::from_str(text).unwrap(), &mut out);
    }
    out
}

/// The first-column keys of the README's table of keys the shipped files leave out.
fn readme_keys() -> BTreeSet<String> {
    let readme = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"),
    )
    .unwrap();
    let start = readme
        .find("The keys below are in no\nshipped file")
        .expect("README: the table of keys the shipped files leave out");
    readme[start..]
        .lines()
        .skip_while(|l| !l.starts_with("| key |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let cell = l.trim_start_matches('|').split('|').next().unwrap().trim();
            cell.trim_matches('`').to_string()
        })
        .collect()
}

#[test]
fn every_accepted_key_is_in_a_shipped_file_or_the_readme() {
    let (shipped, readme) = (shipped_keys(), readme_keys());
    let (tables, accepted) = tables_and_keys();
    // The probe finds the tables there are today, nested ones included.
    for t in [
        "",
        "policy",
        "gp",
        "vilta",
        "initial.scan_jitter",
        "vilta.lead_state",
    ] {
        assert!(
            tables.contains(t),
            "the probe missed the table [{t}]: {tables:?}"
        );
    }
    let undocumented: Vec<&String> = accepted
        .iter()
        .filter(|k| !tables.contains(*k) && !shipped.contains(*k) && !readme.contains(*k))
        .collect();
    assert!(
        undocumented.is_empty(),
        "keys in no shipped file and not in the README's table: {undocumented:?}"
    );
    // And the README lists only keys that exist and that no shipped file sets.
    for k in &readme {
        assert!(
            accepted.contains(k),
            "README lists `{k}`, which no config accepts"
        );
        assert!(
            !shipped.contains(k),
            "README lists `{k}` as left out, but a shipped file sets it"
        );
    }
    assert!(accepted.contains("vilta.lead_state.force_prior_stiffness"));
}
