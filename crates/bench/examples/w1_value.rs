//! Profiler driver: W1 value (+gradient) once; prints J, ‖dJ/dψ‖ and times.
use vicpilco_bench::W1;
use vicpilco_learn::value::value;
fn main() {
    let w1 = W1::load(&vicpilco_bench::default_dir().join("w1.json")).unwrap();
    let pb = w1.problem().unwrap();
    let pred = pb.predictor().unwrap();
    let t = std::time::Instant::now();
    let v = value(&pred, &pb.ret, std::slice::from_ref(&pb.start), false).unwrap();
    println!("J = {:.10} forward {:?}", v.j, t.elapsed());
    let t = std::time::Instant::now();
    let v = value(&pred, &pb.ret, std::slice::from_ref(&pb.start), true).unwrap();
    let g = v.grad.unwrap();
    let n = pb.policy.n_centres() * 6;
    let norm: f64 = g[(6 + 2) * 2..].iter().map(|x| x * x).sum::<f64>().sqrt();
    println!(
        "J = {:.10} value+grad {:?} |dJ/d(inputs,targets)| = {norm:.8} ({n} centre coords)",
        v.j,
        t.elapsed()
    );
}
