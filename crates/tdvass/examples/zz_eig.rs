use tdvass::model::{Params, Plant, Variant, X_T};
fn main() {
    for (v, g) in [
        (Variant::Cs, 0.0),
        (Variant::Pvass, 0.0),
        (Variant::Tdvass, 5386.0),
        (Variant::Tdvass, 40000.0),
        (Variant::Tdvass, -3000.0),
    ] {
        let p = Plant::new(
            Params {
                g,
                ..Params::default()
            },
            v,
        )
        .unwrap();
        let mut a = p.a;
        for r in 0..6 {
            a[(r, X_T)] += p.b[r];
        }
        let ev = a.complex_eigenvalues();
        let m: Vec<f64> = ev.iter().map(|c| c.norm()).collect();
        println!(
            "{v:?} {g}: {:?} bound {}",
            m,
            tdvass::solver::accuracy::rate_bound(&p)
        );
    }
}
