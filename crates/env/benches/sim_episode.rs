//! Check (l): one 10 s episode, GIC at 1 kHz, h = 1e-4 s (100 000 RK4 steps), noise and
//! mismatch on, constant stiffness, no trace. Target ≤ 0.1 s (≥ 100× real time).

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use vicpilco_env::arm::{ArmConfig, ArmEnv, ControllerKind};
use vicpilco_env::Environment;

fn episode(controller: ControllerKind) -> f64 {
    let cfg = ArmConfig {
        controller,
        ..ArmConfig::default()
    };
    let mut env = ArmEnv::new(cfg).expect("valid config");
    env.reset(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0], 1)
        .expect("reset");
    loop {
        let s = env.step(black_box(&[250.0, 250.0])).expect("step");
        if s.done {
            return s.observation[0];
        }
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("sim_episode");
    g.sample_size(20);
    g.bench_function("gic_10s_1khz_h1e-4", |b| {
        b.iter(|| episode(ControllerKind::Gic))
    });
    g.bench_function("sic_10s_1khz_h1e-4", |b| {
        b.iter(|| episode(ControllerKind::Sic))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
