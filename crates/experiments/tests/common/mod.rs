//! Helpers the experiment integration tests share.

use std::path::{Path, PathBuf};

/// A fresh, not yet created directory under the system's temp dir, unique to this test
/// process: `vicpilco-<prefix>-<pid>-<name>`.
pub fn scratch(prefix: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vicpilco-{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Every line of a JSON-lines file (`rollouts.jsonl`, `final_eval.jsonl`, ...), parsed.
// Each test binary compiles this module; not every one reads JSON lines.
#[allow(dead_code)]
pub fn json_lines(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}
