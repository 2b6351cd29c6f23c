//! Rigid-body dynamics of the planar 3R arm in the horizontal plane (g(q) = 0):
//! M(q) q̈ + C(q, q̇) q̇ = τ − F_v q̇ − Jᵀ W_ext  (eq. 2-7).
//!
//! Closed form. With absolute link angles θ = T q (T lower-triangular ones) the kinetic energy
//! is ½ θ̇ᵀ M^θ θ̇ + ½ q̇ᵀ I_m q̇ with
//! M^θ_jk = D_jk cos(θ_j − θ_k) + δ_jk I_j,  D_jk = Σ_{i ≥ max(j,k)} m_i a_ij a_ik,
//! where a_ij = l_j for j < i and a_ii = lc_i (the centre of mass of link i). Lagrange gives
//! C^θ_jk = D_jk sin(θ_j − θ_k) θ̇_k (the Christoffel form, so Ṁ − 2C is skew), and
//! M = Tᵀ M^θ T + diag(I_m), C = Tᵀ C^θ T. [`rnea`] is an independent recursive Newton–Euler
//! used to check both.

use super::kinematics::{abs_rates, Trig};
use super::mat3::{M3, V3};
use super::params::ArmParams;

/// Precomputed inertial coefficients of one arm (the plant or the controller's model).
#[derive(Clone, Debug, PartialEq)]
pub struct ArmModel {
    /// The parameters these were computed from.
    pub params: ArmParams,
    /// D_jk of the module doc.
    d: M3,
}

impl ArmModel {
    /// Precomputes the coefficients.
    pub fn new(params: &ArmParams) -> ArmModel {
        let (l, m, lc) = (params.length, params.mass, params.com);
        let a = |i: usize, j: usize| -> f64 {
            if j < i {
                l[j]
            } else if j == i {
                lc[i]
            } else {
                0.0
            }
        };
        let mut d = [[0.0; 3]; 3];
        for (j, row) in d.iter_mut().enumerate() {
            for (k, v) in row.iter_mut().enumerate() {
                *v = (j.max(k)..3).map(|i| m[i] * a(i, j) * a(i, k)).sum();
            }
        }
        ArmModel {
            params: params.clone(),
            d,
        }
    }

    /// Link lengths.
    #[inline]
    pub fn lengths(&self) -> &V3 {
        &self.params.length
    }

    /// cos(θ_j − θ_k) and sin(θ_j − θ_k) for the pairs (0,1), (0,2), (1,2).
    #[inline]
    fn diffs(t: &Trig) -> ([f64; 3], [f64; 3]) {
        let cd = |j: usize, k: usize| t.c[j] * t.c[k] + t.s[j] * t.s[k];
        let sd = |j: usize, k: usize| t.s[j] * t.c[k] - t.c[j] * t.s[k];
        (
            [cd(0, 1), cd(0, 2), cd(1, 2)],
            [sd(0, 1), sd(0, 2), sd(1, 2)],
        )
    }

    /// Joint-space inertia matrix M(q), symmetric positive definite.
    #[inline]
    pub fn mass_matrix(&self, t: &Trig) -> M3 {
        let d = &self.d;
        let p = &self.params;
        let (c, _) = Self::diffs(t);
        // M^θ (symmetric)
        let a00 = d[0][0] + p.inertia[0];
        let a11 = d[1][1] + p.inertia[1];
        let a22 = d[2][2] + p.inertia[2];
        let a01 = d[0][1] * c[0];
        let a02 = d[0][2] * c[1];
        let a12 = d[1][2] * c[2];
        // M = Tᵀ M^θ T: M_jk = Σ_{a ≥ j} Σ_{b ≥ k} M^θ_ab
        let m22 = a22;
        let m12 = a12 + a22;
        let m02 = a02 + a12 + a22;
        let m11 = a11 + 2.0 * a12 + a22;
        let m01 = a01 + a02 + a11 + 2.0 * a12 + a22;
        let m00 = a00 + a11 + a22 + 2.0 * (a01 + a02 + a12);
        let im = &p.motor_inertia;
        [
            [m00 + im[0], m01, m02],
            [m01, m11 + im[1], m12],
            [m02, m12, m22 + im[2]],
        ]
    }

    /// Coriolis/centrifugal matrix C(q, q̇) (Christoffel form: Ṁ − 2C is skew-symmetric).
    pub fn coriolis_matrix(&self, t: &Trig, qd: &V3) -> M3 {
        let d = &self.d;
        let w = abs_rates(qd);
        let (_, s) = Self::diffs(t);
        // C^θ_jk = D_jk sin(θ_j − θ_k) θ̇_k
        let mut ct = [[0.0; 3]; 3];
        ct[0][1] = d[0][1] * s[0] * w[1];
        ct[1][0] = -d[0][1] * s[0] * w[0];
        ct[0][2] = d[0][2] * s[1] * w[2];
        ct[2][0] = -d[0][2] * s[1] * w[0];
        ct[1][2] = d[1][2] * s[2] * w[2];
        ct[2][1] = -d[1][2] * s[2] * w[1];
        // C = Tᵀ C^θ T: C_jk = Σ_{a ≥ j} Σ_{b ≥ k} C^θ_ab
        let mut r = [[0.0; 3]; 3];
        for (j, row) in r.iter_mut().enumerate() {
            for (k, v) in row.iter_mut().enumerate() {
                let mut acc = 0.0;
                for ca in &ct[j..] {
                    for cab in &ca[k..] {
                        acc += cab;
                    }
                }
                *v = acc;
            }
        }
        r
    }

    /// C(q, q̇) q̇ without forming C (the hot path).
    #[inline]
    pub fn coriolis_vector(&self, t: &Trig, qd: &V3) -> V3 {
        let d = &self.d;
        let w = abs_rates(qd);
        let (_, s) = Self::diffs(t);
        let w2 = [w[0] * w[0], w[1] * w[1], w[2] * w[2]];
        // h^θ_j = Σ_k D_jk sin(θ_j − θ_k) θ̇_k²
        let h0 = d[0][1] * s[0] * w2[1] + d[0][2] * s[1] * w2[2];
        let h1 = -d[0][1] * s[0] * w2[0] + d[1][2] * s[2] * w2[2];
        let h2 = -d[0][2] * s[1] * w2[0] - d[1][2] * s[2] * w2[1];
        // Tᵀ h^θ: suffix sums
        [h0 + h1 + h2, h1 + h2, h2]
    }

    /// Kinetic energy ½ q̇ᵀ M q̇.
    pub fn kinetic_energy(&self, t: &Trig, qd: &V3) -> f64 {
        let m = self.mass_matrix(t);
        let mut e = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                e += qd[i] * m[i][j] * qd[j];
            }
        }
        0.5 * e
    }

    /// dM/dt along q̇ (analytic), for the skew-symmetry check.
    pub fn mass_matrix_dot(&self, t: &Trig, qd: &V3) -> M3 {
        let d = &self.d;
        let w = abs_rates(qd);
        let (_, s) = Self::diffs(t);
        // d/dt cos(θ_j − θ_k) = −sin(θ_j − θ_k)(θ̇_j − θ̇_k)
        let a01 = -d[0][1] * s[0] * (w[0] - w[1]);
        let a02 = -d[0][2] * s[1] * (w[0] - w[2]);
        let a12 = -d[1][2] * s[2] * (w[1] - w[2]);
        let m12 = a12;
        let m02 = a02 + a12;
        let m11 = 2.0 * a12;
        let m01 = a01 + a02 + 2.0 * a12;
        let m00 = 2.0 * (a01 + a02 + a12);
        [[m00, m01, m02], [m01, m11, m12], [m02, m12, 0.0]]
    }
}

/// Recursive Newton–Euler inverse dynamics τ(q, q̇, q̈) in the horizontal plane, written from
/// the free-body diagrams independently of the closed form (used by the tests of M and C).
pub fn rnea(p: &ArmParams, q: &V3, qd: &V3, qdd: &V3) -> V3 {
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    // Forward pass: angular velocity/acceleration, joint and COM accelerations.
    let mut theta = 0.0;
    let mut omega = 0.0;
    let mut alpha = 0.0;
    let mut a_joint = [0.0, 0.0]; // acceleration of joint i's origin
    let mut a_com = [[0.0; 2]; 3];
    let mut r_com = [[0.0; 2]; 3]; // joint i → COM i
    let mut r_link = [[0.0; 2]; 3]; // joint i → joint i+1
    let mut alphas = [0.0; 3];
    for i in 0..3 {
        theta += q[i];
        omega += qd[i];
        alpha += qdd[i];
        let e = [theta.cos(), theta.sin()];
        let rc = [p.com[i] * e[0], p.com[i] * e[1]];
        let rl = [p.length[i] * e[0], p.length[i] * e[1]];
        // a_P = a_O + α × r − ω² r  (planar)
        let acc = |r: [f64; 2]| {
            [
                a_joint[0] - alpha * r[1] - omega * omega * r[0],
                a_joint[1] + alpha * r[0] - omega * omega * r[1],
            ]
        };
        a_com[i] = acc(rc);
        let next = acc(rl);
        r_com[i] = rc;
        r_link[i] = rl;
        alphas[i] = alpha;
        a_joint = next;
    }
    // Backward pass: force f_i and moment n_i that link i−1 exerts on link i at joint i.
    let mut f_next = [0.0, 0.0];
    let mut n_next = 0.0;
    let mut tau = [0.0; 3];
    for i in (0..3).rev() {
        let ma = [p.mass[i] * a_com[i][0], p.mass[i] * a_com[i][1]];
        let f = [ma[0] + f_next[0], ma[1] + f_next[1]];
        let n = n_next + p.inertia[i] * alphas[i] + cross(r_com[i], ma) + cross(r_link[i], f_next);
        tau[i] = n + p.motor_inertia[i] * qdd[i];
        f_next = f;
        n_next = n;
    }
    tau
}

#[cfg(test)]
mod tests {
    use super::super::mat3::mul_mv;
    use super::*;
    use rand::rngs::ChaCha8Rng;
    use rand::{RngExt, SeedableRng};

    /// Check (a): closed-form M and C against RNEA at 100 random states; M SPD; Ṁ − 2C skew.
    #[test]
    fn check_a_closed_form_matches_rnea() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for mismatch in [1.0, 1.15] {
            let p = ArmParams::default().scaled_inertia(mismatch);
            let model = ArmModel::new(&p);
            let mut max_err_m: f64 = 0.0;
            let mut max_err_c: f64 = 0.0;
            let mut max_skew: f64 = 0.0;
            for _ in 0..100 {
                let q: V3 = std::array::from_fn(|_| {
                    rng.random_range(-std::f64::consts::PI..std::f64::consts::PI)
                });
                let qd: V3 = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
                let t = Trig::new(&q);
                let m = model.mass_matrix(&t);
                for k in 0..3 {
                    let mut e = [0.0; 3];
                    e[k] = 1.0;
                    let col = rnea(&p, &q, &[0.0; 3], &e);
                    for i in 0..3 {
                        max_err_m = max_err_m.max((m[i][k] - col[i]).abs());
                    }
                }
                let h = rnea(&p, &q, &qd, &[0.0; 3]);
                let cq = mul_mv(&model.coriolis_matrix(&t, &qd), &qd);
                let hv = model.coriolis_vector(&t, &qd);
                for i in 0..3 {
                    max_err_c = max_err_c
                        .max((cq[i] - h[i]).abs())
                        .max((hv[i] - h[i]).abs());
                }
                // SPD: symmetric with positive leading minors.
                assert!((m[0][1] - m[1][0]).abs() < 1e-15 && (m[0][2] - m[2][0]).abs() < 1e-15);
                assert!(m[0][0] > 0.0);
                assert!(m[0][0] * m[1][1] - m[0][1] * m[1][0] > 0.0);
                assert!(super::super::mat3::det(&m) > 0.0);
                // Ṁ − 2C skew; Ṁ analytic, also checked against a finite difference.
                let md = model.mass_matrix_dot(&t, &qd);
                let c = model.coriolis_matrix(&t, &qd);
                for i in 0..3 {
                    for j in 0..3 {
                        let nij = md[i][j] - 2.0 * c[i][j];
                        let nji = md[j][i] - 2.0 * c[j][i];
                        max_skew = max_skew.max((nij + nji).abs());
                    }
                }
                let e = 1e-6;
                let qp: V3 = std::array::from_fn(|i| q[i] + e * qd[i]);
                let qm: V3 = std::array::from_fn(|i| q[i] - e * qd[i]);
                let (mp, mm) = (
                    model.mass_matrix(&Trig::new(&qp)),
                    model.mass_matrix(&Trig::new(&qm)),
                );
                for i in 0..3 {
                    for j in 0..3 {
                        assert!((md[i][j] - (mp[i][j] - mm[i][j]) / (2.0 * e)).abs() < 1e-7);
                    }
                }
            }
            assert!(max_err_m < 1e-10, "M vs RNEA: {max_err_m:e}");
            assert!(max_err_c < 1e-10, "Cq̇ vs RNEA: {max_err_c:e}");
            assert!(max_skew < 1e-9, "Ṁ − 2C not skew: {max_skew:e}");
        }
    }
}
