//! # Moment matching at an uncertain input
//!
//! For a GP with E outputs and a Gaussian test input `x ~ N(m, s)` (D-dimensional), this
//! module computes exactly (Deisenroth 2010; thesis §3-3-4, eqs. 3-16–3-18):
//!
//! * the predictive mean `M_a = Σ_i β_ai q_ai`, with
//!   `q_ai = σ_fa² |sΛ_a⁻¹ + I|^{-1/2} exp(-½ ν_iᵀ (s+Λ_a)⁻¹ ν_i)` and `ν_i = x_i − m`;
//! * the input-output term `V_a = s⁻¹ Cov[x, f_a] = Σ_i β_ai q_ai (s+Λ_a)⁻¹ ν_i`;
//! * the covariance `S_ab = t_ab β_aᵀ L^{ab} β_b − M_a M_b + δ_ab (σ_fa² − t_aa tr(W_a L^{aa}))`
//!   with `R = s(Λ_a⁻¹+Λ_b⁻¹) + I`, `t_ab = |R|^{-1/2}`,
//!   `L^{ab}_ij = k_a(x_i,m) k_b(x_j,m) exp(½ z_ijᵀ R⁻¹ s z_ij)`, `z_ij = Λ_a⁻¹ν_i + Λ_b⁻¹ν_j`.
//!
//! `W_a` decides the flavour ([`Variance`]):
//! * `(K_a + σ_na² I)⁻¹` — the full GP with model uncertainty (PILCO `gp0`);
//! * `K_mm⁻¹ − B⁻¹` on inducing inputs — the sparse FITC GP (PILCO `gp1`);
//! * none, and a fixed `10⁻⁶` added to the diagonal instead — the GP *mean* as a
//!   deterministic function, the RBF-network policy (PILCO `gp2`).
//!
//! Every flavour has a forward pass ([`forward`]) that returns the moments and a small cache,
//! and a backward pass ([`backward`]) that maps adjoints `(M̄, S̄, V̄)` to adjoints of the input
//! `(m̄, s̄)` and, on request, of the model's centres, `β` and log length-scales and log
//! signal std — the parameters of an RBF policy. The backward pass recomputes the N×N
//! blocks instead of storing them, so memory does not grow with N² × horizon.
//!
//! Covariance adjoints follow one convention throughout vicpilco: `s̄_kl = ∂f/∂s_kl` with the
//! entries of `s` treated as independent, then symmetrised `(s̄ + s̄ᵀ)/2`. For a symmetric
//! perturbation `ds`, `df = Σ_kl s̄_kl ds_kl`.

mod backward;
mod forward;
mod kernels;
mod small;

pub use backward::{backward, InputAdjoint, MomentsAdjoint, ParamAdjoint};
pub use forward::{forward, MmCache, MmModel, Moments, Variance};

#[cfg(test)]
mod tests;
