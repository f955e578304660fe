//! Where wavelet radiosity's light goes: the power of the closed Cornell box lit by its lamp alone
//! (radlab-testkit's `cornell_lamp_lit`), every face of one reflectance ρ, against the energy balance. Closed
//! and of one reflectance, the box absorbs what the lamp emits, so Σ A B over its faces is A_lamp E / (1 − ρ)
//! however unevenly they are lit (Goral, Torrance, Greenberg & Battaile 1984's closure: every point's form
//! factors sum to one). A furnace (every face emitting) tests only the operator's rows; a lamp tests its
//! columns too, where a source's power goes. Prints, per basis, the leaves' power Σ o A B (o their open
//! shares) and the reflected part Σ o A B − A_lamp E against its own balance, as relative errors, with the
//! hierarchical engine's patch transport beside them.
//!
//! `cargo run --release -p radlab-wavelet --example power_balance -- [RHO] [no-blocks] [key=value ...]`
//!
//! Further arguments are the wavelet's parameters (`oracle=f`, `epsilon=0.003`, …; the basis is swept).

use radlab_hierarchical::{Engine, HierarchicalParams, HierarchicalSolver, Patch, Transport};
use radlab_method::{MethodParams, Solver, Step};
use radlab_visibility::Accel;
use radlab_wavelet::{Basis, Engines, WaveletParams, WaveletSolver};

/// Σ o A B (first channel; the scene is grey) over the engine's leaves.
fn power<T: Transport<Patch>>(e: &Engine<Patch, T>) -> f64 {
    (0..e.nodes().len() as u32)
        .filter(|&i| e.is_leaf(i))
        .map(|i| {
            let o = e.open_shares().get(i as usize).copied().unwrap_or(1.0);
            o * e.nodes()[i as usize].area * e.radiosity()[i as usize].x
        })
        .sum()
}

fn run(solver: &mut dyn Solver) -> Result<(), Box<dyn std::error::Error>> {
    while solver.step()? == Step::Continue {}
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut rho = 0.5;
    let mut blocks = true;
    let mut pairs = Vec::new();
    for a in &args {
        match a.split_once('=') {
            Some((k, v)) => pairs.push((k.to_string(), v.to_string())),
            None if a == "no-blocks" => blocks = false,
            None => rho = a.parse()?,
        }
    }
    let lamp = 10.0;
    let scene = radlab_testkit::cornell_lamp_lit(rho, lamp, blocks);
    let accel = Accel::new(&scene);
    let emitted: f64 = (0..scene.face_count())
        .map(|f| scene.faces[f].area * scene.emission(f).x)
        .sum();
    let balance = emitted / (1.0 - rho);
    let report = |name: &str, p: f64, leaves: usize| {
        println!(
            "{name:>12}: power {:+.3}%, reflected {:+.3}%, {leaves} leaves",
            100.0 * (p / balance - 1.0),
            100.0 * ((p - emitted) / (balance - emitted) - 1.0)
        );
    };
    println!("closed lamp-lit Cornell box, rho = {rho}, blocks: {blocks}");
    let mut h = HierarchicalSolver::new(&scene, &accel, HierarchicalParams::default(), 7)?;
    run(&mut h)?;
    report("hierarchical", power(h.engine()), h.engine().leaf_count());
    for basis in [Basis::Haar, Basis::F2, Basis::M2, Basis::M3] {
        let mut p = pairs.clone();
        p.push(("basis".into(), format!("{basis:?}").to_lowercase()));
        let mut s = WaveletSolver::new(&scene, &accel, WaveletParams::from_pairs(&p)?, 7)?;
        run(&mut s)?;
        let (p, n) = match s.engines() {
            Engines::K1(r) => (power(&r.engine), r.engine.leaf_count()),
            Engines::K4(r) => (power(&r.engine), r.engine.leaf_count()),
            Engines::K9(r) => (power(&r.engine), r.engine.leaf_count()),
        };
        report(&format!("{basis:?}"), p, n);
    }
    Ok(())
}
