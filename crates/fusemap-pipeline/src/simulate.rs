//! `fusemap simulate`, planned and run: a scenario file (or the design document's
//! production line) read and checked, the output directory checked against it, then the
//! simulator's recording written as a rosbag2 bag with its ground truth beside it
//! ([`fusemap_sim::bag::simulate_to`]).

use crate::job::JobError;
use fusemap_core::config::LimitsConfig;
use fusemap_sim::bag::{SimulationError, SimulationFiles};
use fusemap_sim::{Scenario, SimRecording};
use std::path::{Path, PathBuf};

/// A simulation, planned.
pub struct SimulateJob {
    /// What is simulated: the scenario file's, or the production line.
    pub scenario: Scenario,
    /// The output directory (`bag/`, `truth.*` inside).
    pub out: PathBuf,
    /// The true map's cell size, metres.
    pub resolution: f64,
    /// Replace what an earlier simulation wrote there.
    pub overwrite: bool,
    /// The memory budget, bytes: a run's with default limits (`simulate` reads no config).
    pub memory_bytes: u64,
}

impl SimulateJob {
    /// `fusemap simulate [SCENARIO] --out DIR`: the scenario read and validated (its errors
    /// name the file and the line), and the bag checked not to replace it.
    pub fn plan(scenario: Option<&Path>, out: &Path, resolution: f64, overwrite: bool) -> Result<Self, JobError> {
        let s = match scenario {
            Some(p) => fusemap_sim::bag::load_scenario(p)?,
            None => Scenario::default(),
        };
        if let Some(p) = scenario {
            fusemap_io::atomic::ensure_not_input(&out.join("bag"), &[p.to_path_buf()])?;
        }
        let memory_bytes = LimitsConfig::default().memory_bytes();
        Ok(Self { scenario: s, out: out.to_path_buf(), resolution, overwrite, memory_bytes })
    }

    /// Simulates and writes the recording and its truth; the recording comes back with
    /// what was written.
    pub fn run(&self) -> Result<(SimRecording, SimulationFiles), JobError> {
        fusemap_sim::bag::simulate_to(&self.scenario, &self.out, self.resolution, self.overwrite, self.memory_bytes)
            .map_err(|e| match e {
                SimulationError::Scenario(e) => JobError::Scenario(e),
                SimulationError::Write(source) => JobError::Simulation { dir: self.out.clone(), source },
            })
    }
}
