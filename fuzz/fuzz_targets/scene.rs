//! A scene file from bytes: it loads, builds, steps 20 times and validates — or it is refused
//! with a typed error. Never a panic, an abort, a hang or a non-finite state.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rugosa::Scene;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(scene) = Scene::from_ron_str(text, "fuzz") else { return };
    let Ok(mut sim) = scene.build() else { return };
    for _ in 0..20 {
        sim.step(sim.settings().time_step);
    }
    if let Err(problem) = sim.validate() {
        panic!("after 20 steps: {problem}");
    }
});
