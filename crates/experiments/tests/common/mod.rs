//! Helpers the experiment integration tests share.

use std::path::Path;

/// A scratch directory under the system's temp dir, `vicpilco-<prefix>-<name>-XXXXXX`,
/// removed when dropped (however the test ends). It derefs to its path.
pub struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A new, empty [`Scratch`] directory.
pub fn scratch(prefix: &str, name: &str) -> Scratch {
    let dir = tempfile::Builder::new()
        .prefix(&format!("vicpilco-{prefix}-{name}-"))
        .tempdir()
        .expect("create a scratch directory");
    Scratch(dir)
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
