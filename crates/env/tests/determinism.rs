//! Check (h): the same seed gives bit-identical traces, also when episodes run on several
//! threads at once; different seeds differ.

mod common;
use common::run;
use std::hash::{DefaultHasher, Hasher};
use vicpilco_env::arm::{ArmConfig, ControllerKind};

/// Hash of every number of the trace and of the observations (SipHash with fixed keys).
fn episode_hash(controller: ControllerKind, seed: u64) -> u64 {
    let cfg = ArmConfig {
        controller,
        ..ArmConfig::default()
    };
    let (env, steps) = run(cfg, [0.5, 0.0], [250.0, 250.0], seed, 40);
    let mut h = DefaultHasher::new();
    for r in env.trace() {
        for b in r.bits() {
            h.write_u64(b);
        }
    }
    for s in &steps {
        for v in &s.observation {
            h.write_u64(v.to_bits());
        }
    }
    h.finish()
}

#[test]
fn check_h_same_seed_same_bits() {
    let jobs: Vec<(ControllerKind, u64)> = [ControllerKind::Gic, ControllerKind::Sic]
        .into_iter()
        .flat_map(|c| [(c, 1), (c, 2)])
        .collect();
    let serial: Vec<u64> = jobs.iter().map(|&(c, s)| episode_hash(c, s)).collect();
    let again: Vec<u64> = jobs.iter().map(|&(c, s)| episode_hash(c, s)).collect();
    assert_eq!(serial, again);
    // Every job twice, all at once on separate threads.
    let threaded: Vec<u64> = std::thread::scope(|scope| {
        let handles: Vec<_> = jobs
            .iter()
            .chain(jobs.iter())
            .map(|&(c, s)| scope.spawn(move || episode_hash(c, s)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(&threaded[..jobs.len()], &serial[..]);
    assert_eq!(&threaded[jobs.len()..], &serial[..]);
    eprintln!("(h) hashes {serial:x?}");
    // Different seeds (and controllers) differ.
    assert_ne!(serial[0], serial[1]);
    assert_ne!(serial[2], serial[3]);
    assert_ne!(serial[0], serial[2]);
}
