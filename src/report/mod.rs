//! Recording a run and writing it out: the event log and the body states as CSV files, and
//! (feature `plot`) PNG plots and animation frames. The columns are listed in `docs/scenes.md`.
//! Every picture of a run gives a body the same colour, [`body_colour`], and the same name,
//! [`Recording::body_name`].
//!
//! ```
//! use rugosa::report::Recording;
//! use rugosa::{BodyDesc, Generator, Rugosity, Simulation, SimulationSettings};
//!
//! let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
//! let disc = Generator::Circle { radius: 0.2 }.build(16).unwrap();
//! sim.add_body(BodyDesc::new(disc, Rugosity::constant(16, 0.002).unwrap()).named("disc")).unwrap();
//! let mut recording = Recording::new(&sim, 1);
//! for _ in 0..10 {
//!     sim.step(sim.settings().time_step);
//!     recording.record_step(&mut sim);
//! }
//! let mut csv = Vec::new();
//! recording.write_states_csv(&mut csv).unwrap();
//! assert_eq!(String::from_utf8(csv).unwrap().lines().count(), 1 + 11);
//! ```

mod palette;
#[cfg(feature = "plot")]
pub mod plot;

pub use palette::{BODY_PALETTE, STATIC_GREY, body_colour};

use std::collections::HashMap;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use hecs::Entity;
use thiserror::Error;

use crate::components::{BodyName, RigidState, Static};
use crate::events::{ContactEvent, EventKind};
use crate::geometry::rugosity::Rugosity;
use crate::geometry::spline::Spline;
use crate::simulation::Simulation;

/// The machine a report was measured on, for its header: the CPU model (from `sysinfo`) and the
/// number of threads the system offers this process. Feature `cli`: the examples' reports use it.
#[cfg(feature = "cli")]
#[must_use]
pub fn machine_description() -> String {
    use sysinfo::{CpuRefreshKind, RefreshKind, System};
    let system = System::new_with_specifics(RefreshKind::nothing().with_cpu(CpuRefreshKind::nothing()));
    let brand = system.cpus().first().map(|cpu| cpu.brand().trim()).filter(|brand| !brand.is_empty());
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    format!("{}, {cores} cores available", brand.unwrap_or("unknown CPU"))
}

/// The median the reports print: the middle of the sorted samples, for an even count the upper
/// of the two middle ones (a measured value, never an average); `None` for no samples.
///
/// ```
/// use std::time::Duration;
/// assert_eq!(rugosa::report::median([3, 1, 2, 4]), Some(3));
/// assert_eq!(rugosa::report::median(Vec::<Duration>::new()), None);
/// ```
#[must_use]
pub fn median<T: Ord + Copy>(samples: impl IntoIterator<Item = T>) -> Option<T> {
    let mut sorted: Vec<T> = samples.into_iter().collect();
    sorted.sort_unstable();
    sorted.get(sorted.len() / 2).copied()
}

/// Columns of `events.csv`, one row per impulse.
pub const EVENT_COLUMNS: [&str; 22] = [
    "event",
    "time",
    "body_a",
    "body_b",
    "segment_a",
    "parameter_a",
    "segment_b",
    "parameter_b",
    "point_x",
    "point_y",
    "normal_x",
    "normal_y",
    "lambda_a",
    "lambda_b",
    "mu_a",
    "mu_b",
    "mu",
    "kind",
    "normal_velocity_before",
    "normal_velocity_after",
    "impulse_x",
    "impulse_y",
];

/// Columns of `states.csv`, one row per body per sampled step.
pub const STATE_COLUMNS: [&str; 8] = ["time", "body", "x", "y", "angle", "vx", "vy", "omega"];

/// Why a report could not be written.
#[derive(Debug, Error)]
pub enum ReportError {
    /// A file or directory could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: io::Error,
    },
    /// A plot could not be drawn.
    #[error("cannot draw {}: {message}", path.display())]
    Plot {
        /// The image file.
        path: PathBuf,
        /// The plotting library's message.
        message: String,
    },
}

/// What a report needs to know about a body: its name, whether it moves, and its shape.
#[derive(Clone, Debug)]
pub struct BodyInfo {
    /// The body's name, or its spawn index as text: the `body` columns of the CSV files.
    pub label: String,
    /// The body's name ([`BodyName`]), if it was given one.
    pub name: Option<String>,
    /// Whether the body is static.
    pub is_static: bool,
    /// The boundary in the body frame (centred on the centre of mass).
    pub spline: Spline,
    /// The per-segment tolerances.
    pub rugosity: Rugosity,
}

/// The state of one body at one sampled time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateSample {
    /// Simulation time (s).
    pub time: f64,
    /// Body index (spawn order), into [`Recording::bodies`].
    pub body: usize,
    /// Position, angle and velocities.
    pub state: RigidState,
}

/// One impulse, with its bodies resolved to indices into [`Recording::bodies`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EventRecord {
    /// Index of body A.
    pub body_a: usize,
    /// Index of body B.
    pub body_b: usize,
    /// The event as logged by the simulation.
    pub event: ContactEvent,
}

/// Everything recorded from a run: bodies, sampled states and every event.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The bodies in spawn order.
    pub bodies: Vec<BodyInfo>,
    /// States, every `state_every`-th step (and at time 0), body by body.
    pub states: Vec<StateSample>,
    /// Every impulse, in application order.
    pub events: Vec<EventRecord>,
    /// Sampling interval of `states`, in steps (≥ 1).
    pub state_every: usize,
    steps: usize,
    slots: HashMap<Entity, usize>,
}

impl Recording {
    /// Starts a recording of `sim`'s bodies, sampling states every `state_every` steps (0 is
    /// taken as 1); the initial states are sampled at once.
    #[must_use]
    pub fn new(sim: &Simulation, state_every: usize) -> Self {
        let entities: Vec<Entity> = sim.bodies().collect();
        let bodies = entities.iter().enumerate().filter_map(|(i, &e)| body_info(sim, e, i)).collect();
        let slots = entities.iter().enumerate().map(|(i, &e)| (e, i)).collect();
        let mut recording =
            Self { bodies, states: Vec::new(), events: Vec::new(), state_every: state_every.max(1), steps: 0, slots };
        recording.sample_states(sim);
        recording
    }

    /// Records one step just taken: drains the simulation's events and samples the states if
    /// this step is a multiple of `state_every`.
    pub fn record_step(&mut self, sim: &mut Simulation) {
        self.steps += 1;
        let slots = &self.slots;
        let resolved = sim.drain_events().filter_map(|event| {
            Some(EventRecord { body_a: *slots.get(&event.body_a)?, body_b: *slots.get(&event.body_b)?, event })
        });
        self.events.extend(resolved);
        if self.steps.is_multiple_of(self.state_every) {
            self.sample_states(sim);
        }
    }

    fn sample_states(&mut self, sim: &Simulation) {
        let time = sim.time();
        for (body, entity) in sim.bodies().enumerate() {
            if let Some(state) = sim.state(entity) {
                self.states.push(StateSample { time, body, state });
            }
        }
    }

    /// Steps recorded so far.
    #[must_use]
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Number of events of each kind, in [`EventKind::ALL`] order.
    #[must_use]
    pub fn events_by_kind(&self) -> [(EventKind, usize); 5] {
        EventKind::ALL.map(|kind| (kind, self.events.iter().filter(|e| e.event.kind == kind).count()))
    }

    /// The time of the last sampled state (s).
    #[must_use]
    pub fn end_time(&self) -> f64 {
        self.states.last().map_or(0.0, |s| s.time)
    }

    /// Writes `events.csv`: a header of [`EVENT_COLUMNS`], then one row per event.
    ///
    /// # Errors
    /// The writer's I/O error.
    pub fn write_events_csv(&self, out: impl Write) -> io::Result<()> {
        let mut csv = csv::Writer::from_writer(out);
        csv.write_record(EVENT_COLUMNS).map_err(into_io_error)?;
        for (index, record) in self.events.iter().enumerate() {
            let e = &record.event;
            csv.write_record([
                index.to_string(),
                e.time.to_string(),
                self.label(record.body_a).to_owned(),
                self.label(record.body_b).to_owned(),
                e.segment_a.to_string(),
                e.parameter_a.to_string(),
                e.segment_b.to_string(),
                e.parameter_b.to_string(),
                e.point.x.to_string(),
                e.point.y.to_string(),
                e.normal.x.to_string(),
                e.normal.y.to_string(),
                e.lambda_a.to_string(),
                e.lambda_b.to_string(),
                e.mu_a.to_string(),
                e.mu_b.to_string(),
                e.mu.to_string(),
                e.kind.name().to_owned(),
                e.normal_velocity_before.to_string(),
                e.normal_velocity_after.to_string(),
                e.impulse.x.to_string(),
                e.impulse.y.to_string(),
            ])
            .map_err(into_io_error)?;
        }
        csv.flush()
    }

    /// Writes `states.csv`: a header of [`STATE_COLUMNS`], then one row per sample.
    ///
    /// # Errors
    /// The writer's I/O error.
    pub fn write_states_csv(&self, out: impl Write) -> io::Result<()> {
        let mut csv = csv::Writer::from_writer(out);
        csv.write_record(STATE_COLUMNS).map_err(into_io_error)?;
        for sample in &self.states {
            let s = &sample.state;
            csv.write_record([
                sample.time.to_string(),
                self.label(sample.body).to_owned(),
                s.position.x.to_string(),
                s.position.y.to_string(),
                s.angle.to_string(),
                s.linear_velocity.x.to_string(),
                s.linear_velocity.y.to_string(),
                s.angular_velocity.to_string(),
            ])
            .map_err(into_io_error)?;
        }
        csv.flush()
    }

    /// Writes `dir/events.csv` and `dir/states.csv`, creating `dir` if needed.
    ///
    /// # Errors
    /// [`ReportError::Io`] naming the file.
    pub fn write_csv_files(&self, dir: &Path) -> Result<(), ReportError> {
        create_dir(dir)?;
        let events = dir.join("events.csv");
        self.write_events_csv(create_file(&events)?).map_err(|e| io_error(&events, e))?;
        let states = dir.join("states.csv");
        self.write_states_csv(create_file(&states)?).map_err(|e| io_error(&states, e))
    }

    fn label(&self, body: usize) -> &str {
        self.bodies.get(body).map_or("?", |b| b.label.as_str())
    }

    /// The name pictures give body `body` (an index into [`Recording::bodies`]): its
    /// [`BodyName`] if it has one, else `body <index>`.
    ///
    /// ```
    /// use rugosa::report::Recording;
    /// use rugosa::{BodyDesc, Generator, Rugosity, Simulation, SimulationSettings};
    ///
    /// let mut sim = Simulation::new(SimulationSettings::default()).unwrap();
    /// let disc = Generator::Circle { radius: 0.2 }.build(16).unwrap();
    /// let rugosity = Rugosity::constant(16, 0.002).unwrap();
    /// sim.add_body(BodyDesc::new(disc.clone(), rugosity.clone()).named("wheel")).unwrap();
    /// sim.add_body(BodyDesc::new(disc, rugosity)).unwrap();
    /// let recording = Recording::new(&sim, 1);
    /// assert_eq!(recording.body_name(0), "wheel");
    /// assert_eq!(recording.body_name(1), "body 1");
    /// assert_eq!(recording.pair_name(0, 1), "wheel – body 1");
    /// ```
    #[must_use]
    pub fn body_name(&self, body: usize) -> String {
        match self.bodies.get(body).and_then(|b| b.name.as_deref()) {
            Some(name) => name.to_owned(),
            None => format!("body {body}"),
        }
    }

    /// The name pictures give the pair of bodies `a` and `b`: `"<name a> – <name b>"` (an en
    /// dash between [`Recording::body_name`]s).
    #[must_use]
    pub fn pair_name(&self, a: usize, b: usize) -> String {
        format!("{} – {}", self.body_name(a), self.body_name(b))
    }
}

fn body_info(sim: &Simulation, entity: Entity, index: usize) -> Option<BodyInfo> {
    let world = sim.world();
    let name = world.get::<&BodyName>(entity).ok().map(|n| n.0.clone());
    Some(BodyInfo {
        label: name.clone().unwrap_or_else(|| index.to_string()),
        name,
        is_static: world.get::<&Static>(entity).is_ok(),
        spline: Spline::clone(&*world.get::<&Spline>(entity).ok()?),
        rugosity: Rugosity::clone(&*world.get::<&Rugosity>(entity).ok()?),
    })
}

/// The I/O error under a CSV writer's error. Records of one fixed width of text can only fail
/// to be written, so any other kind is not expected; it is passed on as [`io::ErrorKind::Other`].
fn into_io_error(error: csv::Error) -> io::Error {
    match error.into_kind() {
        csv::ErrorKind::Io(error) => error,
        other => io::Error::other(format!("{other:?}")),
    }
}

pub(crate) fn io_error(path: &Path, source: io::Error) -> ReportError {
    ReportError::Io { path: path.to_owned(), source }
}

pub(crate) fn create_dir(dir: &Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, e))
}

fn create_file(path: &Path) -> Result<std::fs::File, ReportError> {
    std::fs::File::create(path).map_err(|e| io_error(path, e))
}
