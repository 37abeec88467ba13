//! Fuzzes the scene parser and validator: any input must give a scene or a SceneError naming
//! a field — never a panic. Valid scenes are also checked for the invariants validation
//! promises (finite, in-domain parameters and tolerances).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match stickslip::scene::parse(&text, "fuzz") {
        Ok(scene) => {
            let p = scene.params;
            assert!(p.gamma.is_finite() && p.gamma > 0.0 && p.xi.is_finite() && p.xi > 0.0 && p.epsilon.is_finite());
            assert!(scene.solver.rtol.is_finite() && scene.solver.rtol > 0.0);
            assert!(scene.solver.atol.iter().all(|a| a.is_finite() && *a >= 0.0));
            assert!(scene.initial.iter().all(|x| x.is_finite()));
        }
        Err(e) => assert!(!e.field.is_empty() && !e.message.is_empty(), "{e}"),
    }
});
