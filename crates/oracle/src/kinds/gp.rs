//! Checkers for the GP kinds: `gp0` (full GP with model uncertainty), `gp2` (GP mean as a
//! function, with derivatives w.r.t. its training set and hyper-parameters).
//!
//! Full Jacobians are assembled from the reverse-mode pass, one unit adjoint per output entry,
//! which checks the VJPs themselves.

use super::blocks::compute_err;
use crate::{compare, Case, Class, Comparison, KindChecker, OracleError, Tensor, Tolerance};
use faer::Mat;
use vicpilco_gp::moments::{backward, forward, MmCache, MmModel, Moments, MomentsAdjoint};
use vicpilco_gp::{GpModel, SparseGpModel};

pub struct Gp0;
pub struct Gp2;
pub struct Gp1;

pub(crate) fn load_gp(case: &Case) -> Result<GpModel, OracleError> {
    let inputs = case.mat("inputs")?;
    let targets = case.mat("targets")?;
    GpModel::new(inputs, targets, case.hypers("hyp")?).map_err(|e| compute_err(case, e))
}

/// Which output entry a unit adjoint selects.
#[derive(Clone, Copy)]
enum Out {
    Mean(usize),
    Cov(usize, usize),
    V(usize, usize),
}

/// Jacobians of (M, S, V) w.r.t. m, s and (optionally) the GP's inputs, targets, hyp.
struct Jacobians {
    wrt_m: [Tensor; 3],
    wrt_s: [Tensor; 3],
    wrt_data: Option<[[Tensor; 3]; 3]>,
}

fn jacobians(
    mm: &MmModel<'_>,
    gp: Option<&GpModel>,
    cache: &MmCache,
    d: usize,
    e: usize,
) -> Result<Jacobians, String> {
    let n = mm.centres.nrows();
    let outs: [Vec<Out>; 3] = [
        (0..e).map(Out::Mean).collect(),
        (0..e)
            .flat_map(|i| (0..e).map(move |j| Out::Cov(i, j)))
            .collect(),
        (0..d)
            .flat_map(|k| (0..e).map(move |a| Out::V(k, a)))
            .collect(),
    ];
    let prefixes = [vec![e], vec![e, e], vec![d, e]];
    let mut wrt_m: Vec<Tensor> = Vec::new();
    let mut wrt_s: Vec<Tensor> = Vec::new();
    let mut wrt_data: Vec<[Tensor; 3]> = Vec::new();
    for (outs, prefix) in outs.iter().zip(&prefixes) {
        let mut dm = Vec::new();
        let mut ds = Vec::new();
        let (mut di, mut dt, mut dx) = (Vec::new(), Vec::new(), Vec::new());
        for &o in outs {
            let mut mbar = vec![0.0; e];
            let mut sbar = Mat::<f64>::zeros(e, e);
            let mut vbar = Mat::<f64>::zeros(d, e);
            match o {
                Out::Mean(a) => mbar[a] = 1.0,
                Out::Cov(i, j) => sbar[(i, j)] = 1.0,
                Out::V(k, a) => vbar[(k, a)] = 1.0,
            }
            let adj = MomentsAdjoint {
                mean: &mbar,
                cov: sbar.as_ref(),
                v: vbar.as_ref(),
            };
            let ia = backward(mm, cache, adj, gp.is_some()).map_err(|e| e.to_string())?;
            dm.extend_from_slice(&ia.m);
            for k in 0..d {
                for l in 0..d {
                    ds.push(ia.s[(k, l)]);
                }
            }
            if let (Some(gp), Some(p)) = (gp, ia.params.as_ref()) {
                let full = gp.chain_param_adjoint(p);
                di.extend(
                    (0..n)
                        .flat_map(|r| (0..d).map(move |c| (r, c)))
                        .map(|(r, c)| full.inputs[(r, c)]),
                );
                dt.extend(
                    (0..n)
                        .flat_map(|r| (0..e).map(move |c| (r, c)))
                        .map(|(r, c)| full.targets[(r, c)]),
                );
                dx.extend(
                    (0..d + 2)
                        .flat_map(|r| (0..e).map(move |c| (r, c)))
                        .map(|(r, c)| full.hyp[c][r]),
                );
            }
        }
        let shape = |suffix: &[usize]| prefix.iter().chain(suffix).copied().collect::<Vec<_>>();
        wrt_m.push(Tensor::new(shape(&[d]), dm));
        wrt_s.push(Tensor::new(shape(&[d, d]), ds));
        if gp.is_some() {
            wrt_data.push([
                Tensor::new(shape(&[n, d]), di),
                Tensor::new(shape(&[n, e]), dt),
                Tensor::new(shape(&[d + 2, e]), dx),
            ]);
        }
    }
    let arr3 = |v: Vec<Tensor>| -> [Tensor; 3] { v.try_into().expect("three outputs") };
    Ok(Jacobians {
        wrt_m: arr3(wrt_m),
        wrt_s: arr3(wrt_s),
        wrt_data: if wrt_data.is_empty() {
            None
        } else {
            Some(wrt_data.try_into().unwrap_or_else(|_| unreachable!()))
        },
    })
}

/// Compare the moments and their derivatives; `data_names` are the suffixes of the
/// training-set derivative fields (gp2: `i`, `t`, `X`).
pub(crate) fn compare_moments(
    case: &Case,
    mm: &MmModel<'_>,
    gp_for_params: Option<&GpModel>,
    moments: &Moments,
    cache: &MmCache,
) -> Result<Vec<Comparison>, OracleError> {
    let tol = Tolerance::for_case(&case.kind, &case.name);
    let (d, e) = (mm.input_dim(), mm.output_dim());
    let mut out = vec![
        compare(
            "M",
            Class::Value,
            &Tensor::from_vec(&moments.mean),
            &case.tensor("M")?,
            tol,
        ),
        compare(
            "S",
            Class::CovOrDerivative,
            &Tensor::from_mat(&moments.cov),
            &case.tensor("S")?,
            tol,
        ),
        compare(
            "V",
            Class::Value,
            &Tensor::from_mat(&moments.v),
            &case.tensor("V")?,
            tol,
        ),
    ];
    let jac = jacobians(mm, gp_for_params, cache, d, e).map_err(|e| compute_err(case, e))?;
    for (k, name) in ["M", "S", "V"].iter().enumerate() {
        out.push(compare(
            &format!("d{name}dm"),
            Class::CovOrDerivative,
            &jac.wrt_m[k],
            &case.tensor(&format!("d{name}dm"))?,
            tol,
        ));
        out.push(compare(
            &format!("d{name}ds"),
            Class::CovOrDerivative,
            &jac.wrt_s[k],
            &case.cov_derivative(&format!("d{name}ds"))?,
            tol,
        ));
        if let Some(data) = &jac.wrt_data {
            for (t, suffix) in data[k].iter().zip(["i", "t", "X"]) {
                let field = format!("d{name}d{suffix}");
                out.push(compare(
                    &field,
                    Class::CovOrDerivative,
                    t,
                    &case.tensor(&field)?,
                    tol,
                ));
            }
        }
    }
    Ok(out)
}

fn m_and_s(case: &Case) -> Result<(Vec<f64>, Mat<f64>), OracleError> {
    Ok((case.vec("m")?, case.mat("s")?))
}

impl KindChecker for Gp0 {
    fn kind(&self) -> &'static str {
        "gp0"
    }
    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let gp = load_gp(case)?;
        let (m, s) = m_and_s(case)?;
        let mm = MmModel::with_uncertainty(&gp);
        let (moments, cache) = forward(&mm, &m, s.as_ref()).map_err(|e| compute_err(case, e))?;
        compare_moments(case, &mm, None, &moments, &cache)
    }
}

impl KindChecker for Gp2 {
    fn kind(&self) -> &'static str {
        "gp2"
    }
    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let gp = load_gp(case)?;
        let (m, s) = m_and_s(case)?;
        let mm = MmModel::mean_only(&gp);
        let (moments, cache) = forward(&mm, &m, s.as_ref()).map_err(|e| compute_err(case, e))?;
        compare_moments(case, &mm, Some(&gp), &moments, &cache)
    }
}

impl KindChecker for Gp1 {
    fn kind(&self) -> &'static str {
        "gp1"
    }
    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let gp = SparseGpModel::new(
            case.mat("inputs")?.as_ref(),
            case.mat("targets")?.as_ref(),
            case.hypers("hyp")?,
            case.mat("induce")?,
        )
        .map_err(|e| compute_err(case, e))?;
        let (m, s) = m_and_s(case)?;
        let mm = MmModel::sparse(&gp);
        let (moments, cache) = forward(&mm, &m, s.as_ref()).map_err(|e| compute_err(case, e))?;
        compare_moments(case, &mm, None, &moments, &cache)
    }
}
