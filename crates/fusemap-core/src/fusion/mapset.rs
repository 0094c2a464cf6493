//! Several maps fed by one pass over the data, each from its own subset of sensors.
//!
//! The validation of the design document compares leave-one-sensor-out maps built from
//! the same run: M1 = lidar + odometry, M2 = camera + odometry, M3 = everything. Building
//! them in one pass converts each observation into rays once (the sensor model runs once)
//! and inserts it into every map whose [`SensorSelection`] includes its sensor. Each map
//! keeps its own tiles and update marks, so a map built this way is bit for bit the map
//! a separate run with only its sensors would build: maps never see each other's
//! observations, and each applies its own in the same time order.

use crate::grid::{InsertStats, OccupancyGrid};
use crate::measurement::{RangeData, SensorId, SensorKind};

/// Which sensors a map takes observations from. (Odometry is not selected here: it places
/// observations, it does not observe the map.)
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SensorSelection {
    /// Every sensor.
    All,
    /// Every sensor of these kinds.
    Kinds(Vec<SensorKind>),
    /// Exactly these sensors.
    Sensors(Vec<SensorId>),
}

impl SensorSelection {
    /// Whether an observation of `sensor`, of kind `kind`, goes into the map.
    #[inline]
    pub fn includes(&self, sensor: SensorId, kind: SensorKind) -> bool {
        match self {
            SensorSelection::All => true,
            SensorSelection::Kinds(k) => k.contains(&kind),
            SensorSelection::Sensors(s) => s.contains(&sensor),
        }
    }
}

/// One map of a [`MapSet`] with its sensor selection and counters.
pub struct MapEntry {
    name: String,
    sensors: SensorSelection,
    grid: OccupancyGrid,
    stats: InsertStats,
}

impl MapEntry {
    fn new(name: String, sensors: SensorSelection, grid: OccupancyGrid) -> Self {
        Self { name, sensors, grid, stats: InsertStats::default() }
    }

    /// The map's name (`M1`, `lidar-only`, …).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The sensors it takes.
    pub fn sensors(&self) -> &SensorSelection {
        &self.sensors
    }

    /// The map.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// Consumes the entry, returning the map.
    pub fn into_grid(self) -> OccupancyGrid {
        self.grid
    }

    /// What the insertions into this map did, summed.
    pub fn stats(&self) -> &InsertStats {
        &self.stats
    }
}

/// Maps fed by one engine pass; never empty (the first map is the engine's primary map,
/// the one [`Engine::grid`](super::Engine::grid) returns).
pub struct MapSet {
    primary: MapEntry,
    others: Vec<MapEntry>,
}

impl MapSet {
    /// A set whose first (primary) map is `grid`, named `name`, taking `sensors`.
    pub fn new(name: impl Into<String>, sensors: SensorSelection, grid: OccupancyGrid) -> Self {
        Self { primary: MapEntry::new(name.into(), sensors, grid), others: Vec::new() }
    }

    /// Adds a map and returns its index.
    pub fn add(&mut self, name: impl Into<String>, sensors: SensorSelection, grid: OccupancyGrid) -> usize {
        self.others.push(MapEntry::new(name.into(), sensors, grid));
        self.others.len()
    }

    /// Adds a map (builder form).
    pub fn with(mut self, name: impl Into<String>, sensors: SensorSelection, grid: OccupancyGrid) -> Self {
        self.add(name, sensors, grid);
        self
    }

    /// Number of maps (at least one).
    pub fn len(&self) -> usize {
        1 + self.others.len()
    }

    /// Never true: a set holds its primary map.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The map at `index` (0 is the primary map).
    pub fn get(&self, index: usize) -> Option<&MapEntry> {
        match index {
            0 => Some(&self.primary),
            i => self.others.get(i - 1),
        }
    }

    /// The map named `name` (the first, if several share it).
    pub fn by_name(&self, name: &str) -> Option<&MapEntry> {
        self.iter().find(|m| m.name == name)
    }

    /// The primary map.
    pub fn primary(&self) -> &MapEntry {
        &self.primary
    }

    /// All maps, primary first.
    pub fn iter(&self) -> impl Iterator<Item = &MapEntry> {
        std::iter::once(&self.primary).chain(&self.others)
    }

    /// Consumes the set, returning its maps in order, primary first.
    pub fn into_entries(self) -> Vec<MapEntry> {
        std::iter::once(self.primary).chain(self.others).collect()
    }

    /// Consumes the set, returning the primary map.
    pub fn into_primary(self) -> OccupancyGrid {
        self.primary.grid
    }

    /// Inserts one observation of a sensor of kind `kind` into every map that takes it.
    /// Returns the summed insertion counts and the number of maps fed.
    pub fn insert(&mut self, kind: SensorKind, data: &RangeData) -> (InsertStats, u64) {
        let mut total = InsertStats::default();
        let mut fed = 0;
        for m in std::iter::once(&mut self.primary).chain(&mut self.others) {
            if m.sensors.includes(data.sensor, kind) {
                let s = m.grid.insert(data);
                m.stats.add(&s);
                total.add(&s);
                fed += 1;
            }
        }
        (total, fed)
    }
}
