//! Reading one oracle case file: nested JSON arrays become row-major [`Tensor`]s.

use crate::OracleError;
use faer::Mat;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};
use vicpilco_gp::Hyper;

/// A dense array of any rank, row-major (last index fastest), as the oracle stores it.
#[derive(Clone, Debug, PartialEq)]
pub struct Tensor {
    /// Length of each axis, outermost first (the oracle's `[E, E, D]`); empty for a scalar.
    pub shape: Vec<usize>,
    /// The `shape.iter().product()` entries, row-major.
    pub data: Vec<f64>,
}

impl Tensor {
    /// Panics unless `data` holds exactly `shape.iter().product()` entries.
    pub fn new(shape: Vec<usize>, data: Vec<f64>) -> Self {
        assert_eq!(
            shape.iter().product::<usize>(),
            data.len(),
            "tensor shape/data mismatch"
        );
        Self { shape, data }
    }

    /// All entries 0, `shape.iter().product()` of them.
    pub fn zeros(shape: Vec<usize>) -> Self {
        let n = shape.iter().product();
        Self::new(shape, vec![0.0; n])
    }

    /// Rank 0 (shape `[]`), as the oracle stores bare numbers such as `lossSat`'s `L`.
    pub fn scalar(v: f64) -> Self {
        Self::new(vec![], vec![v])
    }

    /// Rank 1, shape `[v.len()]`.
    pub fn from_vec(v: &[f64]) -> Self {
        Self::new(vec![v.len()], v.to_vec())
    }

    /// Rank 2, shape `[rows, cols]`, laid out like the oracle's arrays of rows.
    pub fn from_mat(m: &Mat<f64>) -> Self {
        let (r, c) = (m.nrows(), m.ncols());
        let mut data = Vec::with_capacity(r * c);
        for i in 0..r {
            for j in 0..c {
                data.push(m[(i, j)]);
            }
        }
        Self::new(vec![r, c], data)
    }

    /// The tensor as a matrix; rank-1 tensors become one column.
    pub fn to_mat(&self) -> Mat<f64> {
        match self.shape.len() {
            1 => Mat::from_fn(self.shape[0], 1, |i, _| self.data[i]),
            2 => Mat::from_fn(self.shape[0], self.shape[1], |i, j| {
                self.data[i * self.shape[1] + j]
            }),
            _ => panic!("to_mat on a tensor of shape {:?}", self.shape),
        }
    }

    /// `max |entry|` (0 when empty): the scale of the oracle README's tolerance rule.
    pub fn max_abs(&self) -> f64 {
        self.data.iter().fold(0.0, |a, v| a.max(v.abs()))
    }

    /// Symmetrise over the last two indices (for derivatives w.r.t. a covariance matrix).
    /// Panics unless they exist and are of equal length, as for a tensor vicpilco computed;
    /// a stored one goes through [`Case::cov_derivative`], which names the field instead.
    pub fn symmetrise_last_pair(&mut self) {
        let r = self.shape.len();
        assert!(r >= 2 && self.shape[r - 1] == self.shape[r - 2]);
        let n = self.shape[r - 1];
        for block in self.data.chunks_mut(n * n) {
            for k in 0..n {
                for l in 0..k {
                    let v = 0.5 * (block[k * n + l] + block[l * n + k]);
                    block[k * n + l] = v;
                    block[l * n + k] = v;
                }
            }
        }
    }
}

/// One case file: its kind, name and raw fields.
#[derive(Clone, Debug)]
pub struct Case {
    /// The file's `kind` field (e.g. `gp1`), empty when absent; picks the [`crate::Tolerance`].
    pub kind: String,
    /// The file's `case` field (e.g. `D3_E2_N30_M30_induceX`), else the file stem;
    /// `<parent>.<key>` for a [`Case::sub`].
    pub name: String,
    /// The JSON file it was read from (shared by its sub-cases); errors name it.
    pub path: PathBuf,
    fields: Map<String, Value>,
}

impl Case {
    /// Read one `<kind>/<case>.json`; fails with [`OracleError::Io`], or [`OracleError::Parse`]
    /// when it is not JSON or not an object. Fields are only checked by the typed getters.
    pub fn load(path: &Path) -> Result<Self, OracleError> {
        let text = std::fs::read_to_string(path).map_err(|e| OracleError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let value: Value = serde_json::from_str(&text).map_err(|e| OracleError::Parse {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
        let Value::Object(fields) = value else {
            return Err(OracleError::Parse {
                path: path.to_path_buf(),
                detail: "top level is not a JSON object".into(),
            });
        };
        let kind = fields
            .get("kind")
            .and_then(Value::as_str)
            .unwrap_or_default()
            .to_string();
        let name = fields
            .get("case")
            .and_then(Value::as_str)
            .map(str::to_string)
            .unwrap_or_else(|| {
                path.file_stem()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into()
            });
        Ok(Self {
            kind,
            name,
            path: path.to_path_buf(),
            fields,
        })
    }

    fn field(&self, name: &str) -> Result<&Value, OracleError> {
        self.fields
            .get(name)
            .ok_or_else(|| self.bad(name, "missing"))
    }

    fn bad(&self, field: &str, detail: &str) -> OracleError {
        OracleError::Field {
            path: self.path.clone(),
            field: field.to_string(),
            detail: detail.to_string(),
        }
    }

    /// Field `name` of any rank: nested arrays (first index outermost) flattened row-major, a
    /// bare number as rank 0. Fails when the field is missing, ragged or not numeric.
    pub fn tensor(&self, name: &str) -> Result<Tensor, OracleError> {
        let mut shape = Vec::new();
        let mut data = Vec::new();
        flatten(self.field(name)?, 0, &mut shape, &mut data).map_err(|d| self.bad(name, &d))?;
        Ok(Tensor::new(shape, data))
    }

    /// Field `name` stored as an array of rows; fails unless it has rank 2.
    pub fn mat(&self, name: &str) -> Result<Mat<f64>, OracleError> {
        let t = self.tensor(name)?;
        if t.shape.len() != 2 {
            return Err(self.bad(name, &format!("expected a matrix, shape {:?}", t.shape)));
        }
        Ok(t.to_mat())
    }

    /// Field `name` stored as a flat array; fails unless it has rank 1 (a bare number fails).
    pub fn vec(&self, name: &str) -> Result<Vec<f64>, OracleError> {
        let t = self.tensor(name)?;
        if t.shape.len() != 1 {
            return Err(self.bad(name, &format!("expected a vector, shape {:?}", t.shape)));
        }
        Ok(t.data)
    }

    /// Field `name` stored as a bare JSON number (`[x]` fails), e.g. `gamma`.
    pub fn scalar(&self, name: &str) -> Result<f64, OracleError> {
        self.field(name)?
            .as_f64()
            .ok_or_else(|| self.bad(name, "expected a number"))
    }

    /// A size such as `D`, `P` or `H`: a bare number that must be a non-negative integer.
    pub fn usize(&self, name: &str) -> Result<usize, OracleError> {
        let v = self.scalar(name)?;
        if v < 0.0 || v.fract() != 0.0 {
            return Err(self.bad(name, "expected a non-negative integer"));
        }
        Ok(v as usize)
    }

    /// Field `name` stored as a JSON string, e.g. `policy_type` of the value cases.
    pub fn string(&self, name: &str) -> Result<String, OracleError> {
        self.field(name)?
            .as_str()
            .map(str::to_string)
            .ok_or_else(|| self.bad(name, "expected a string"))
    }

    /// An index set stored 1-based (`*_1based`), returned 0-based.
    pub fn indices_1based(&self, name: &str) -> Result<Vec<usize>, OracleError> {
        let t = self.tensor(name)?;
        t.data
            .iter()
            .map(|&v| {
                if v < 1.0 || v.fract() != 0.0 {
                    Err(self.bad(name, &format!("{v} is not a 1-based index")))
                } else {
                    Ok(v as usize - 1)
                }
            })
            .collect()
    }

    /// A PILCO hyper-parameter column `[log ℓ_1..log ℓ_D; log σ_f; log σ_n]` of field `name`
    /// needs D ≥ 1, so at least 3 entries.
    fn check_hyp_len(&self, name: &str, len: usize) -> Result<(), OracleError> {
        if len >= 3 {
            return Ok(());
        }
        Err(self.bad(
            name,
            &format!("expected [log ℓ_1..log ℓ_D; log σ_f; log σ_n] with D ≥ 1, got {len} entries"),
        ))
    }

    /// PILCO's hyper-parameter matrix `name`, one column per output (see
    /// [`Self::hyper`]).
    pub fn pilco_hyp(&self, name: &str) -> Result<Mat<f64>, OracleError> {
        let hyp = self.mat(name)?;
        self.check_hyp_len(name, hyp.nrows())?;
        Ok(hyp)
    }

    /// [`Self::pilco_hyp`] as one [`Hyper`] per column (output).
    pub fn hypers(&self, name: &str) -> Result<Vec<Hyper>, OracleError> {
        let hyp = self.pilco_hyp(name)?;
        (0..hyp.ncols())
            .map(|e| {
                Hyper::from_pilco(&(0..hyp.nrows()).map(|r| hyp[(r, e)]).collect::<Vec<_>>())
                    .map_err(|err| self.bad(name, &err.to_string()))
            })
            .collect()
    }

    /// One output's PILCO hyper-parameter vector `name`: `[log ℓ_1..log ℓ_D, log σ_f,
    /// log σ_n]`, at least 3 entries.
    pub fn hyper(&self, name: &str) -> Result<Hyper, OracleError> {
        let col = self.vec(name)?;
        self.check_hyp_len(name, col.len())?;
        Hyper::from_pilco(&col).map_err(|err| self.bad(name, &err.to_string()))
    }

    /// The Gaussian input `m` (length `d`) and `s` (`d`×`d`) of a moment-matching case.
    pub fn gaussian_input(&self, d: usize) -> Result<(Vec<f64>, Mat<f64>), OracleError> {
        self.gaussian("m", "s", d)
    }

    /// A Gaussian stored as fields `mean` (length `d`) and `cov` (`d`×`d`), e.g. the value
    /// cases' start `m0`, `S0`; fails naming the field of the wrong size.
    pub fn gaussian(
        &self,
        mean: &str,
        cov: &str,
        d: usize,
    ) -> Result<(Vec<f64>, Mat<f64>), OracleError> {
        let (m, s) = (self.vec(mean)?, self.mat(cov)?);
        if m.len() != d {
            return Err(self.bad(mean, &format!("expected length {d}, got {}", m.len())));
        }
        if (s.nrows(), s.ncols()) != (d, d) {
            return Err(self.bad(
                cov,
                &format!("expected {d}×{d}, got {}×{}", s.nrows(), s.ncols()),
            ));
        }
        Ok((m, s))
    }

    /// Field `name`, a derivative w.r.t. a covariance matrix, symmetrised over its last two
    /// indices ([`Tensor::symmetrise_last_pair`]); fails naming the field unless it has two
    /// last indices of equal length.
    pub fn cov_derivative(&self, name: &str) -> Result<Tensor, OracleError> {
        let mut t = self.tensor(name)?;
        let r = t.shape.len();
        if r < 2 || t.shape[r - 1] != t.shape[r - 2] {
            return Err(self.bad(
                name,
                &format!(
                    "expected the last two axes of equal length (a derivative w.r.t. a \
                     covariance), shape {:?}",
                    t.shape
                ),
            ));
        }
        t.symmetrise_last_pair();
        Ok(t)
    }

    /// A nested object (e.g. `prop1` of the value cases) as a case of its own.
    pub fn sub(&self, name: &str) -> Result<Case, OracleError> {
        match self.field(name)? {
            Value::Object(m) => Ok(Case {
                kind: self.kind.clone(),
                name: format!("{}.{}", self.name, name),
                path: self.path.clone(),
                fields: m.clone(),
            }),
            _ => Err(self.bad(name, "expected an object")),
        }
    }
}

fn flatten(
    v: &Value,
    depth: usize,
    shape: &mut Vec<usize>,
    out: &mut Vec<f64>,
) -> Result<(), String> {
    match v {
        Value::Number(n) => {
            if depth != shape.len() {
                return Err("ragged array".into());
            }
            out.push(n.as_f64().ok_or("number out of range")?);
            Ok(())
        }
        Value::Array(items) => {
            if depth == shape.len() {
                if !out.is_empty() {
                    return Err("ragged array".into());
                }
                shape.push(items.len());
            } else if depth > shape.len() || shape[depth] != items.len() {
                return Err("ragged array".into());
            }
            for item in items {
                flatten(item, depth + 1, shape, out)?;
            }
            Ok(())
        }
        _ => Err(format!("expected numbers, found {v}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_arrays_flatten_row_major() {
        let v: Value = serde_json::from_str("[[[1,2],[3,4]],[[5,6],[7,8]]]").unwrap();
        let (mut s, mut d) = (vec![], vec![]);
        flatten(&v, 0, &mut s, &mut d).unwrap();
        assert_eq!(s, vec![2, 2, 2]);
        assert_eq!(d, vec![1., 2., 3., 4., 5., 6., 7., 8.]);
    }

    #[test]
    fn ragged_arrays_are_rejected() {
        let v: Value = serde_json::from_str("[[1,2],[3]]").unwrap();
        let (mut s, mut d) = (vec![], vec![]);
        assert!(flatten(&v, 0, &mut s, &mut d).is_err());
    }

    #[test]
    fn empty_array_has_shape_zero() {
        let v: Value = serde_json::from_str("[]").unwrap();
        let (mut s, mut d) = (vec![], vec![]);
        flatten(&v, 0, &mut s, &mut d).unwrap();
        assert_eq!(s, vec![0]);
        assert!(d.is_empty());
    }
}
