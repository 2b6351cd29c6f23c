//! Shared code of the checkers for PILCO's small blocks (`gSat`, `gTrig`, `conlin`,
//! `lossSat`): full Jacobians built from vicpilco's reverse-mode VJPs by unit adjoints, laid
//! out as the oracle stores them (`dYdx` has shape `shape(Y) ++ shape(x)`, derivatives w.r.t.
//! a covariance symmetrised over the last index pair).

use crate::{compare, Case, Class, Comparison, OracleError, Tensor, Tolerance};
use faer::Mat;
use vicpilco_pilco::{GaussianBar, Moments, MomentsBar};

pub(crate) fn compute_err(case: &Case, e: impl std::fmt::Display) -> OracleError {
    OracleError::Compute {
        path: case.path.clone(),
        detail: e.to_string(),
    }
}

/// Derivatives of one output array (flattened row-major, `n` entries) w.r.t. the input mean,
/// the input covariance and (optionally) the parameters.
pub(crate) struct Jacobian {
    pub dm: Tensor,
    pub ds: Tensor,
    pub dp: Tensor,
}

/// Build the Jacobians of an output of shape `shape` from `vjp(flat entry) → (m̄, s̄, p̄)`.
pub(crate) fn jacobian(
    shape: &[usize],
    d: usize,
    p: usize,
    mut vjp: impl FnMut(usize) -> (GaussianBar, Vec<f64>),
) -> Jacobian {
    let n: usize = shape.iter().product();
    let (mut dm, mut ds, mut dp) = (
        Vec::with_capacity(n * d),
        Vec::with_capacity(n * d * d),
        Vec::with_capacity(n * p),
    );
    for k in 0..n {
        let (g, pb) = vjp(k);
        dm.extend_from_slice(&g.mean);
        for a in 0..d {
            for b in 0..d {
                ds.push(g.cov[(a, b)]);
            }
        }
        dp.extend_from_slice(&pb);
    }
    let with = |extra: &[usize]| shape.iter().chain(extra).copied().collect::<Vec<_>>();
    let mut ds = Tensor::new(with(&[d, d]), ds);
    ds.symmetrise_last_pair();
    Jacobian {
        dm: Tensor::new(with(&[d]), dm),
        ds,
        dp: Tensor::new(with(&[p]), dp),
    }
}

/// Compare a stored array with ours.
pub(crate) fn cmp(
    case: &Case,
    out: &mut Vec<Comparison>,
    field: &str,
    class: Class,
    got: &Tensor,
) -> Result<(), OracleError> {
    let want = case.tensor(field)?;
    let tol = Tolerance::for_case(&case.kind, &case.name);
    out.push(compare(field, class, got, &want, tol));
    Ok(())
}

/// Check a Gaussian-to-Gaussian block (`M`, `S`, and `C` or `V` under the name `c_name`) and
/// every derivative array of it the case stores: w.r.t. `m`, `s` and, when `p > 0`, the flat
/// parameters (`d?dp`).
pub(crate) fn check_moment_block(
    case: &Case,
    d: usize,
    p: usize,
    c_name: &str,
    outputs: &Moments,
    mut vjp: impl FnMut(&MomentsBar) -> (GaussianBar, Vec<f64>),
) -> Result<Vec<Comparison>, OracleError> {
    let e = outputs.mean.len();
    let mut out = Vec::new();
    cmp(
        case,
        &mut out,
        "M",
        Class::Value,
        &Tensor::from_vec(&outputs.mean),
    )?;
    cmp(
        case,
        &mut out,
        "S",
        Class::CovOrDerivative,
        &Tensor::from_mat(&outputs.cov),
    )?;
    cmp(
        case,
        &mut out,
        c_name,
        Class::Value,
        &Tensor::from_mat(&outputs.v),
    )?;

    let zero = || MomentsBar {
        mean: vec![0.0; e],
        cov: Mat::zeros(e, e),
        v: None,
    };
    let jm = jacobian(&[e], d, p, |k| {
        let mut bar = zero();
        bar.mean[k] = 1.0;
        vjp(&bar)
    });
    let js = jacobian(&[e, e], d, p, |k| {
        let mut bar = zero();
        bar.cov[(k / e, k % e)] = 1.0;
        vjp(&bar)
    });
    let jc = jacobian(&[d, e], d, p, |k| {
        let mut bar = zero();
        let mut c = Mat::zeros(d, e);
        c[(k / e, k % e)] = 1.0;
        bar.v = Some(c);
        vjp(&bar)
    });
    for (y, j) in [("M", &jm), ("S", &js), (c_name, &jc)] {
        let deriv = Class::CovOrDerivative;
        cmp(case, &mut out, &format!("d{y}dm"), deriv, &j.dm)?;
        cmp(case, &mut out, &format!("d{y}ds"), deriv, &j.ds)?;
        if p > 0 {
            cmp(case, &mut out, &format!("d{y}dp"), deriv, &j.dp)?;
        }
    }
    Ok(out)
}

/// Check a policy case: moments, every derivative (w.r.t. m, s and the flat parameters) and
/// the flat parameter order `p_flat`.
pub(crate) fn check_policy<P: vicpilco_pilco::policy::Policy>(
    case: &Case,
    pol: &P,
) -> Result<Vec<Comparison>, OracleError> {
    let d = case.usize("D")?;
    if pol.n_inputs() != d || pol.n_params() != case.usize("P")? {
        return Err(compute_err(
            case,
            "the policy's sizes disagree with D and P",
        ));
    }
    let (m, s) = case.gaussian_input(d)?;
    let (outputs, cache) = pol
        .forward(&m, s.as_ref())
        .map_err(|e| compute_err(case, e))?;
    let p = pol.n_params();
    let mut out = check_moment_block(case, d, p, "V", &outputs, |bar| {
        let mut pb = vec![0.0; p];
        let g = pol.backward(&cache, bar, &mut pb);
        (g, pb)
    })?;
    cmp(
        case,
        &mut out,
        "p_flat",
        Class::Value,
        &Tensor::from_vec(&pol.params()),
    )?;
    Ok(out)
}
