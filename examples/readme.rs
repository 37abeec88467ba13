//! The README's five lines of Rust: the earthquake scene through the library, as
//! `stickslip run` computes it. tools/test.sh runs this example from the repository's root;
//! tests/readme.rs checks that the README shows these lines verbatim.
//!
//!     cargo run --release --example readme

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string("data/scenes/earthquake.json")?;
    let scene = stickslip::scene::parse(&text, "earthquake.json")?;
    let report = stickslip::engine::run(&scene, Default::default())?;
    let cycle = report.cycle.and_then(|c| c.values).ok_or("no limit cycle")?.main;
    println!("period {:.6}, v_max {:.4e} (dimensionless)", cycle.period, cycle.v_max);
    Ok(())
}
