//! The scenes, described once as rugosa bodies; the peers get the same bodies through
//! [`crate::shapes`].

#[path = "../../../tests/common/pile.rs"]
mod pile;

use glam::DVec2;
use rugosa::{BodyDesc, FrictionLaw, Generator, Material, Rugosity, Scene, SimulationSettings, SleepSettings};

use crate::shapes::Natural;

/// Bodies turned rigidly about a pivot at a constant rate (the tumbler's container).
#[derive(Clone, Debug)]
pub struct Drive {
    /// Pivot (m).
    pub pivot: DVec2,
    /// Angular velocity (rad/s).
    pub omega: f64,
    /// The driven (kinematic) bodies, scene order.
    pub bodies: Vec<usize>,
}

/// A scene both engines run.
#[derive(Clone, Debug)]
pub struct SceneSpec {
    /// Short name for tables.
    pub name: String,
    /// Bodies in spawn order.
    pub bodies: Vec<BodyDesc>,
    /// The exact shape each body approximates, where the peers have it (scene order).
    pub natural: Vec<Option<Natural>>,
    /// Kinematic bodies driven each step, if any.
    pub drive: Option<Drive>,
    /// Settings of rugosa (gravity and time step are given to rapier too).
    pub settings: SimulationSettings,
    /// Size of a dynamic body (m): the mean diameter of the dynamic bodies' curves (largest
    /// distance between two control points); geometric tolerances and errors are relative to it.
    pub body_size: f64,
}

impl SceneSpec {
    /// A scene of `bodies` with no natural shapes and no drive.
    #[must_use]
    pub fn new(name: impl Into<String>, bodies: Vec<BodyDesc>, settings: SimulationSettings) -> Self {
        let moving: Vec<f64> = bodies.iter().filter(|b| !b.is_static && !b.is_kinematic).map(diameter).collect();
        let body_size = moving.iter().sum::<f64>() / moving.len().max(1) as f64;
        let natural = vec![None; bodies.len()];
        Self { name: name.into(), bodies, natural, drive: None, settings, body_size }
    }

    /// The same scene with body `index`'s natural shape given.
    #[must_use]
    pub fn with_natural(mut self, index: usize, natural: Natural) -> Self {
        self.natural[index] = Some(natural);
        self
    }

    /// Number of dynamic bodies.
    #[must_use]
    pub fn dynamic_count(&self) -> usize {
        self.bodies.iter().filter(|b| !b.is_static && !b.is_kinematic).count()
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
    // Sleeping is chosen per run for every engine (`engine::Setup::sleep`).
    SimulationSettings { record_events: false, sleep: SleepSettings::off(), ..SimulationSettings::default() }
}

/// The pile of `examples/performance_report.rs`: a box of static walls and `count` blobs
/// (16 segments, radius 0.1 m, band 2 mm, λ_min 1 mm, μ_max 0.6) in a grid above it.
#[must_use]
pub fn pile(count: usize) -> SceneSpec {
    blobs_in_box(format!("pile of {count} blobs"), count, pile::square_columns(count))
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
    pyramids(1, base)
}

/// `count` pyramids of base `base` side by side on one ground slab, 2 m apart (Box2D's
/// `many_pyramids`, smaller).
#[must_use]
pub fn pyramids(count: usize, base: usize) -> SceneSpec {
    let band = 0.005;
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.75 }, ..Material::default() };
    let pitch = 1.0 + PYRAMID_GAP;
    let spacing = base as f64 * pitch + 2.0;
    let ground_width = count as f64 * spacing + 10.0;
    let ground =
        Generator::RoundedRectangle { width: ground_width, height: 1.0, corner_radius: 0.1 }.build(32).unwrap();
    let mut bodies = vec![
        BodyDesc::new(ground, Rugosity::constant(32, band).unwrap())
            .with_material(material)
            .at(DVec2::new(0.0, -0.5), 0.0)
            .fixed(),
    ];
    for pyramid in 0..count {
        let centre = (pyramid as f64 - 0.5 * (count as f64 - 1.0)) * spacing;
        for row in 0..base {
            let width = base - row;
            for column in 0..width {
                let x = centre + (column as f64 - 0.5 * (width as f64 - 1.0)) * pitch;
                let y = 0.5 + PYRAMID_GAP + row as f64 * pitch;
                // 24 segments: the fewest a rounded rectangle takes (6 control points per corner).
                let spline =
                    Generator::RoundedRectangle { width: 1.0, height: 1.0, corner_radius: 0.1 }.build(24).unwrap();
                let rugosity = Rugosity::constant(24, band).unwrap();
                bodies.push(BodyDesc::new(spline, rugosity).with_material(material).at(DVec2::new(x, y), 0.0));
            }
        }
    }
    let name = if count == 1 { format!("pyramid, base {base}") } else { format!("{count} pyramids, base {base}") };
    let mut spec = SceneSpec::new(name, bodies, base_settings());
    let rounded = Natural::RoundedBox { half: DVec2::splat(0.5), radius: 0.1 };
    for index in 1..spec.bodies.len() {
        spec = spec.with_natural(index, rounded);
    }
    spec
}

/// Box2D's tumbler, smaller: a 4 m square container of four kinematic walls (rounded
/// rectangles 0.2 m thick, band 2 mm) turning at 0.5 rad/s about its centre, holding `count`
/// blobs of the pile in a grid.
#[must_use]
pub fn tumbler(count: usize) -> SceneSpec {
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.6 }, ..Material::default() };
    let side = 4.0;
    let pivot = DVec2::new(0.0, side);
    let wall = |size: DVec2, at: DVec2| {
        let spline =
            Generator::RoundedRectangle { width: size.x, height: size.y, corner_radius: 0.05 }.build(32).unwrap();
        BodyDesc::new(spline, Rugosity::constant(32, 0.002).unwrap())
            .with_material(material)
            .at(pivot + at, 0.0)
            .kinematic()
    };
    let half = 0.5 * side + 0.1;
    let mut bodies = vec![
        wall(DVec2::new(side + 0.4, 0.2), DVec2::new(0.0, -half)),
        wall(DVec2::new(side + 0.4, 0.2), DVec2::new(0.0, half)),
        wall(DVec2::new(0.2, side), DVec2::new(-half, 0.0)),
        wall(DVec2::new(0.2, side), DVec2::new(half, 0.0)),
    ];
    let columns = ((side - 0.4) / 0.3).floor() as usize;
    bodies.extend((0..count).map(|k| {
        let (i, j) = (k % columns, k / columns);
        let spline = Generator::Blob { radius: 0.1, roughness: 0.5, seed: k as u64 }.build(16).unwrap();
        let at = pivot + DVec2::new(-0.5 * side + 0.35 + 0.3 * i as f64, -0.5 * side + 0.35 + 0.3 * j as f64);
        BodyDesc::new(spline, Rugosity::constant(16, 0.002).unwrap()).with_material(material).at(at, 0.1 * k as f64)
    }));
    let mut spec = SceneSpec::new(format!("tumbler, {count} blobs"), bodies, base_settings());
    spec.drive = Some(Drive { pivot, omega: 0.5, bodies: vec![0, 1, 2, 3] });
    spec
}

/// Rain: `count` blobs of the pile in a sparse column 20 wide, rows 0.8 m apart, falling one
/// row after another into the pile's box.
#[must_use]
pub fn rain(count: usize) -> SceneSpec {
    let columns = 20;
    let mut bodies = pile::blob_pile(0, columns);
    let width = columns as f64 * pile::BLOB_SPACING + 0.5;
    let material = Material { friction: FrictionLaw { lambda_min: 0.001, mu_max: 0.6 }, ..Material::default() };
    bodies.extend((0..count).map(|k| {
        let (i, j) = (k % columns, k / columns);
        let spline = Generator::Blob { radius: 0.1, roughness: 0.5, seed: k as u64 }.build(16).unwrap();
        let x = -0.5 * width + pile::BLOB_SPACING + pile::BLOB_SPACING * i as f64 + 0.1 * (j % 3) as f64;
        let at = DVec2::new(x, 1.0 + 0.8 * j as f64);
        BodyDesc::new(spline, Rugosity::constant(16, 0.002).unwrap()).with_material(material).at(at, 0.1 * k as f64)
    }));
    SceneSpec::new(format!("rain of {count} blobs"), bodies, base_settings())
}
