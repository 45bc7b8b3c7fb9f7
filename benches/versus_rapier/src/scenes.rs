//! The scenes, described once as rugosa bodies; rapier gets the same bodies through
//! [`crate::rapier_world`].

#[path = "../../../tests/common/pile.rs"]
mod pile;

use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Material, Rugosity, SimulationSettings, SleepSettings, scene::Scene};

/// A scene both engines run.
#[derive(Clone, Debug)]
pub struct SceneSpec {
    /// Short name for tables.
    pub name: String,
    /// Bodies in spawn order.
    pub bodies: Vec<BodyDesc>,
    /// Settings of rugosa (gravity and time step are given to rapier too).
    pub settings: SimulationSettings,
    /// Size of a dynamic body (m): the mean diameter of the dynamic bodies' curves (largest
    /// distance between two control points); geometric tolerances and errors are relative to it.
    pub body_size: f64,
}

impl SceneSpec {
    fn new(name: impl Into<String>, bodies: Vec<BodyDesc>, settings: SimulationSettings) -> Self {
        let dynamic: Vec<f64> = bodies.iter().filter(|b| !b.is_static).map(diameter).collect();
        let body_size = dynamic.iter().sum::<f64>() / dynamic.len().max(1) as f64;
        Self { name: name.into(), bodies, settings, body_size }
    }

    /// Number of dynamic bodies.
    #[must_use]
    pub fn dynamic_count(&self) -> usize {
        self.bodies.iter().filter(|b| !b.is_static).count()
    }

    /// The μ rugosa's friction law gives this body at its mean tolerance: what rapier gets.
    #[must_use]
    pub fn friction_of(&self, body: &BodyDesc) -> f64 {
        let tolerances = body.rugosity.tolerances();
        let mean = tolerances.iter().sum::<f64>() / tolerances.len() as f64;
        body.material.friction.coefficient(mean)
    }

    /// The distinct (μ, e) pairs of the scene's bodies, for the report.
    #[must_use]
    pub fn coefficients(&self) -> Vec<(f64, f64)> {
        let mut pairs: Vec<(f64, f64)> = Vec::new();
        for body in &self.bodies {
            let pair = (self.friction_of(body), body.material.restitution);
            if !pairs.iter().any(|p| (p.0 - pair.0).abs() < 1e-9 && (p.1 - pair.1).abs() < 1e-12) {
                pairs.push(pair);
            }
        }
        pairs
    }
}

fn diameter(body: &BodyDesc) -> f64 {
    let points = body.spline.control_points();
    points.iter().flat_map(|a| points.iter().map(move |b| a.distance(*b))).fold(0.0, f64::max)
}

fn base_settings() -> SimulationSettings {
    // Sleeping off in both engines (rapier's bodies are built with sleeping off too).
    SimulationSettings { record_events: false, sleep: SleepSettings::off(), ..SimulationSettings::default() }
}

/// The pile of `examples/performance_report.rs`: a box of static walls and `count` blobs
/// (16 segments, radius 0.1 m, band 2 mm, λ_min 1 mm, μ_max 0.6) in a grid above it.
#[must_use]
pub fn pile(count: usize) -> SceneSpec {
    blobs_in_box(format!("pile of {count} blobs"), count, pile::square_columns(count))
}

/// The accuracy scene: `count` blobs of the pile in one row, 0.35 m apart, dropped 0.2 m onto
/// the floor of the same box (they land at about 0.2 s; the row keeps blob–blob impacts rare,
/// so differences in the step are not amplified by a chain of collisions).
#[must_use]
pub fn row(count: usize) -> SceneSpec {
    blobs_in_box(format!("row of {count} blobs"), count, count)
}

fn blobs_in_box(name: String, count: usize, columns: usize) -> SceneSpec {
    SceneSpec::new(name, pile::blob_pile(count, columns), base_settings())
}

/// The seed's Figure 12: four irregular blobs, one per rugosity type, dropped on a block.
///
/// # Errors
/// The scene file's error, as text.
pub fn fig12() -> Result<SceneSpec, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scenes/fig12-irregular.ron");
    let scene = Scene::load(path).map_err(|e| e.to_string())?;
    let bodies = scene.body_descs().map_err(|e| e.to_string())?;
    let settings = SimulationSettings { record_events: false, ..scene.settings.clone() };
    Ok(SceneSpec::new("Figure 12 (fig12-irregular.ron)", bodies, settings))
}

/// Gap between neighbouring pyramid boxes and above the ground (m): inside the combined band
/// (2 × 5 mm), so the boxes start in contact within tolerance without their curves touching.
pub const PYRAMID_GAP: f64 = 0.004;

/// Box2D's `large_pyramid` with a base of `base` boxes: 1 m rounded squares (corner radius
/// 0.1 m, 16 segments, band 5 mm; λ_min 1 mm and μ_max 0.75 give Box2D's μ = 0.6) stacked in
/// rows of base, base − 1, …, 1 on a static ground slab.
#[must_use]
pub fn pyramid(base: usize) -> SceneSpec {
    let band = 0.005;
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.75 }, ..Material::default() };
    let ground_width = base as f64 + 10.0;
    let ground =
        Generator::RoundedRectangle { width: ground_width, height: 1.0, corner_radius: 0.1 }.build(32).unwrap();
    let mut bodies = vec![
        BodyDesc::new(ground, Rugosity::constant(32, band).unwrap())
            .with_material(material)
            .at(DVec2::new(0.0, -0.5), 0.0)
            .fixed(),
    ];
    let pitch = 1.0 + PYRAMID_GAP;
    for row in 0..base {
        let count = base - row;
        for column in 0..count {
            let x = (column as f64 - 0.5 * (count as f64 - 1.0)) * pitch;
            let y = 0.5 + PYRAMID_GAP + row as f64 * pitch;
            // 24 segments: the fewest a rounded rectangle takes (6 control points per corner).
            let spline = Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
            let rugosity = Rugosity::constant(24, band).unwrap();
            bodies.push(BodyDesc::new(spline, rugosity).with_material(material).at(DVec2::new(x, y), 0.0));
        }
    }
    SceneSpec::new(format!("pyramid, base {base}"), bodies, base_settings())
}
