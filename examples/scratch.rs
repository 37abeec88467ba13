use stickslip::analysis::{cycle, hopf};
use stickslip::integrate::*;
use stickslip::model::*;
use stickslip::sundials::*;
fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().unwrap()).collect();
    let (gamma, xi, eps, rtol) = (args[0], args[1], args[2], args[3]);
    let method = args.get(4).copied().unwrap_or(0.0) as i32;
    let drr = Drr::new(DrrParams { gamma, xi, epsilon: eps, friction: Friction::Log });
    let w0 = 0.5f64.ln();
    let y0 = [drr.manifold_u(w0, 0.0), w0, 0.0];
    let opts = Options::new(rtol, Tolerance::Scalar(rtol * 1e-2));
    let t = std::time::Instant::now();
    let mut integ: Box<dyn Integrator> = match method {
        0 => Box::new(Solver::cvode(drr, CvodeSettings::default(), 0.0, &y0, &opts).unwrap()),
        _ => {
            let table = std::env::var("TABLE").map(|n| DirkTable::from_name(&n).unwrap()).unwrap_or_default();
            let mut opts = opts.clone();
            if let Ok(v) = std::env::var("ETF") { opts.max_err_test_fails = Some(v.parse().unwrap()); }
            if let Ok(v) = std::env::var("NLI") { opts.max_nonlin_iters = Some(v.parse().unwrap()); }
            if let Ok(v) = std::env::var("NCC") { opts.nonlin_conv_coef = Some(v.parse().unwrap()); }
            let pm = std::env::var("PRED").ok().map(|v| v.parse().unwrap());
            Box::new(Solver::arkstep(drr, ArkMethod::Dirk(table), ArkSettings { predictor_method: pm, deduce_implicit_rhs: std::env::var("DEDUCE").is_ok() }, 0.0, &y0, &opts).unwrap())
        }
    };
    let h = hopf::analyse(&drr);
    let r = cycle::analyse(integ.as_mut(), &drr, &cycle::CycleSettings::defaults(rtol, rtol * 1e-2), h.max_real_part < 0.0);
    let el = t.elapsed();
    match r {
        Ok(r) => { println!("{:?} cycles {} used {}", r.status, r.cycles_computed, r.cycles_used);
            if let Some(v) = r.values { println!("{v:#?}"); } println!("spread {:?}", r.spread.map(|s| (s.period, s.ln_v_max)));
            for c in r.last_cycles.iter().chain(&r.orbit) { println!("P {} lnvmax {}", c.period, c.ln_v_max); } }
        Err(e) => println!("ERR {e}"),
    }
    println!("{:?}\n{:?}", integ.stats(), el);
}
