use stickslip::integrate::*;
use stickslip::sundials::*;
struct Fast;
impl OdeSystem for Fast {
    fn dim(&self) -> usize { 1 }
    fn rhs(&self, t: f64, _y: &[f64], d: &mut [f64]) { d[0] = (1e7 * (t - 1e10)).cos(); }
}
fn main() {
    let mut options = Options::new(1e-10, Tolerance::Scalar(1e-14));
    options.max_steps = Some(5000);
    let t0 = 1e10;
    let mut s = Solver::cvode(Fast, CvodeSettings::default(), t0, &[0.0], &options).unwrap();
    let r = s.advance(t0 + 1e-3, Task::Normal);
    println!("{r:?}\n{:?}\n{:?}", s.stats(), s.warnings());
}
