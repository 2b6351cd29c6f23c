//! A JSON value plus where it came from, so every type error can name the file and the field
//! path (`episodes[3].recorded_return`) instead of serde's line/column.

use crate::ReportError;
use serde_json::Value;
use std::path::Path;

#[derive(Clone, Copy)]
pub(crate) struct Node<'a> {
    pub file: &'a Path,
    /// Rendered lazily into errors only; a linked list avoids building strings on the happy path.
    at: Loc<'a>,
    pub v: &'a Value,
}

#[derive(Clone, Copy)]
enum Loc<'a> {
    Root(&'a str),
    Key(&'a Loc<'a>, &'a str),
    Index(&'a Loc<'a>, usize),
}

impl Loc<'_> {
    fn render(&self) -> String {
        match self {
            Loc::Root(prefix) => (*prefix).to_string(),
            Loc::Key(parent, key) => {
                let p = parent.render();
                if p.is_empty() || p.ends_with(": ") {
                    format!("{p}{key}")
                } else {
                    format!("{p}.{key}")
                }
            }
            Loc::Index(parent, i) => format!("{}[{i}]", parent.render()),
        }
    }
}

/// A short description of a JSON value for error messages.
fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("the boolean {b}"),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => {
            let short: String = s.chars().take(40).collect();
            let more = if s.chars().count() > 40 { "…" } else { "" };
            format!("the string {short:?}{more}")
        }
        Value::Array(a) => format!("an array of {} elements", a.len()),
        Value::Object(_) => "an object".into(),
    }
}

impl<'a> Node<'a> {
    /// `prefix` names the record inside the file ("" for a whole-file document, "line 3: " for
    /// one line of a .jsonl file).
    pub fn root(file: &'a Path, prefix: &'a str, v: &'a Value) -> Self {
        Node {
            file,
            at: Loc::Root(prefix),
            v,
        }
    }

    pub fn field(&self) -> String {
        let s = self.at.render();
        let s = s.trim_end_matches(": ");
        if s.is_empty() {
            "(top level)".into()
        } else {
            s.into()
        }
    }

    pub fn malformed(&self, expected: impl Into<String>) -> ReportError {
        ReportError::Malformed {
            file: self.file.to_path_buf(),
            field: self.field(),
            expected: expected.into(),
            found: describe(self.v),
        }
    }

    fn missing(&self, key: &str) -> ReportError {
        let field = Loc::Key(&self.at, key).render();
        ReportError::Missing {
            file: self.file.to_path_buf(),
            field: field.trim_end_matches(": ").into(),
        }
    }

    /// Calls `f` with the child `key`, or `None` if it is absent or null. The child borrows a
    /// location that lives only for the call, hence the closure.
    pub fn with<T>(&self, key: &str, f: impl FnOnce(Option<Node<'_>>) -> T) -> T {
        let loc = Loc::Key(&self.at, key);
        match self.v.get(key) {
            None | Some(Value::Null) => f(None),
            Some(v) => f(Some(Node {
                file: self.file,
                at: loc,
                v,
            })),
        }
    }

    /// Like [`Node::with`], but an absent child is a `Missing` error.
    pub fn req<T>(
        &self,
        key: &str,
        f: impl FnOnce(Node<'_>) -> Result<T, ReportError>,
    ) -> Result<T, ReportError> {
        self.with(key, |n| match n {
            Some(n) => f(n),
            None => Err(self.missing(key)),
        })
    }

    /// Applies `f` to every element of an array.
    pub fn map_array<T>(
        &self,
        mut f: impl FnMut(Node<'_>) -> Result<T, ReportError>,
    ) -> Result<Vec<T>, ReportError> {
        let items = self
            .v
            .as_array()
            .ok_or_else(|| self.malformed("an array"))?;
        items
            .iter()
            .enumerate()
            .map(|(i, v)| {
                f(Node {
                    file: self.file,
                    at: Loc::Index(&self.at, i),
                    v,
                })
            })
            .collect()
    }

    pub fn f64(&self) -> Result<f64, ReportError> {
        self.v.as_f64().ok_or_else(|| self.malformed("a number"))
    }

    pub fn u64(&self) -> Result<u64, ReportError> {
        self.v
            .as_u64()
            .ok_or_else(|| self.malformed("a non-negative integer"))
    }

    pub fn bool(&self) -> Result<bool, ReportError> {
        self.v
            .as_bool()
            .ok_or_else(|| self.malformed("true or false"))
    }

    pub fn string(&self) -> Result<String, ReportError> {
        self.v
            .as_str()
            .map(str::to_string)
            .ok_or_else(|| self.malformed("a string"))
    }

    pub fn f64_vec(&self) -> Result<Vec<f64>, ReportError> {
        self.map_array(|n| n.f64())
    }

    pub fn f64_rows(&self) -> Result<Vec<Vec<f64>>, ReportError> {
        self.map_array(|n| n.f64_vec())
    }

    pub fn string_vec(&self) -> Result<Vec<String>, ReportError> {
        self.map_array(|n| n.string())
    }

    pub fn req_f64(&self, key: &str) -> Result<f64, ReportError> {
        self.req(key, |n| n.f64())
    }

    pub fn req_u64(&self, key: &str) -> Result<u64, ReportError> {
        self.req(key, |n| n.u64())
    }

    pub fn opt_f64(&self, key: &str) -> Result<Option<f64>, ReportError> {
        self.with(key, |n| n.map(|n| n.f64()).transpose())
    }

    pub fn opt_u64(&self, key: &str) -> Result<Option<u64>, ReportError> {
        self.with(key, |n| n.map(|n| n.u64()).transpose())
    }

    pub fn opt_bool(&self, key: &str) -> Result<Option<bool>, ReportError> {
        self.with(key, |n| n.map(|n| n.bool()).transpose())
    }

    pub fn opt_string(&self, key: &str) -> Result<Option<String>, ReportError> {
        self.with(key, |n| n.map(|n| n.string()).transpose())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn errors_name_the_nested_field() {
        let v = json!({"episodes": [{"a": 1}, {"a": "x"}]});
        let file = Path::new("summary.json");
        let root = Node::root(file, "", &v);
        let err = root
            .req("episodes", |n| n.map_array(|e| e.req_f64("a")))
            .unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("summary.json"), "{msg}");
        assert!(msg.contains("episodes[1].a"), "{msg}");
        assert!(msg.contains("the string \"x\""), "{msg}");

        let err = root
            .req("episodes", |n| n.map_array(|e| e.req_f64("b")))
            .unwrap_err();
        assert!(matches!(&err, ReportError::Missing { field, .. } if field == "episodes[0].b"));
    }

    #[test]
    fn line_prefix_and_null_as_absent() {
        let v = json!({"rollout": {"costs": null, "actions": [[1.0], [true]]}});
        let file = Path::new("rollouts.jsonl");
        let root = Node::root(file, "line 3: ", &v);
        let costs = root.req("rollout", |r| r.with("costs", |c| Ok(c.is_none())));
        assert!(costs.unwrap());
        let err = root
            .req("rollout", |r| r.req("actions", |a| a.f64_rows()))
            .unwrap_err();
        assert!(
            err.to_string().contains("line 3: rollout.actions[1][0]"),
            "{err}"
        );
        let err = root.req("episode", |n| n.u64()).unwrap_err();
        assert!(matches!(&err, ReportError::Missing { field, .. } if field == "line 3: episode"));
        assert_eq!(Node::root(file, "", &v).field(), "(top level)");
    }
}
