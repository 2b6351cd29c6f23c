//! `nlml`: negative log marginal likelihood of one output and its gradient, plain and with
//! PILCO's `hypCurb` penalty (oracle README, "nlml").

use crate::{compare, Case, Class, Comparison, KindChecker, OracleError, Tensor, Tolerance};
use vicpilco_gp::train::{input_std, nlml, HypCurb};

pub struct Nlml;

impl KindChecker for Nlml {
    fn kind(&self) -> &'static str {
        "nlml"
    }

    fn check(&self, case: &Case) -> Result<Vec<Comparison>, OracleError> {
        let inputs = case.mat("inputs")?;
        let targets = case.vec("targets")?;
        let hyp = case.hyper("hyp")?;
        let curb = HypCurb {
            power: case.usize("curb_power")? as i32,
            ls: case.scalar("curb_ls")?,
            snr: case.scalar("curb_snr")?,
        };
        let refused = |e: vicpilco_gp::GpError| OracleError::Compute {
            path: case.path.clone(),
            detail: e.to_string(),
        };
        let plain = nlml(inputs.as_ref(), &targets, &hyp).map_err(refused)?;
        // c_d is recomputed from the inputs (and compared), not read from the file.
        let std = input_std(inputs.as_ref());
        let (pen, dpen) = curb.penalty(&hyp, &std).map_err(refused)?;
        let curbed: Vec<f64> = plain.grad.iter().zip(&dpen).map(|(a, b)| a + b).collect();

        let tol = Tolerance::for_case(&case.kind, &case.name);
        let want = |f: &str| case.tensor(f);
        Ok(vec![
            compare(
                "nlml",
                Class::Value,
                &Tensor::scalar(plain.value),
                &want("nlml")?,
                tol,
            ),
            compare(
                "dnlml",
                Class::CovOrDerivative,
                &Tensor::from_vec(&plain.grad),
                &want("dnlml")?,
                tol,
            ),
            compare(
                "nlml_curb",
                Class::Value,
                &Tensor::scalar(plain.value + pen),
                &want("nlml_curb")?,
                tol,
            ),
            compare(
                "dnlml_curb",
                Class::CovOrDerivative,
                &Tensor::from_vec(&curbed),
                &want("dnlml_curb")?,
                tol,
            ),
            compare(
                "curb_std",
                Class::Value,
                &Tensor::from_vec(&std),
                &want("curb_std")?,
                tol,
            ),
        ])
    }
}
