//! Several maps fed by one pass over the data, each from its own subset of sensors.
//!
//! The validation of the design document compares leave-one-sensor-out maps built from
//! the same run: M1 = lidar + odometry, M2 = camera + odometry, M3 = everything. Building
//! them in one pass converts each observation into rays once (the sensor model runs once)
//! and inserts it into every map whose [`SensorSelection`] includes its sensor. Each map
//! keeps its own tiles and update marks, so a map built this way is bit for bit the map
//! a separate run with only its sensors would build: maps never see each other's
//! observations, and each applies its own in the same time order.

use crate::grid::{DynamicUpdate, FusedUpdate, FusionGrid, Group, InsertStats};
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
    /// Every sensor but those named (a lidar's name also leaves out the sensors of its
    /// other frames, `name@frame`): §4.3's leave-one-out maps, chosen before the sensors
    /// have ids. `ids` is filled as the engine registers the named sensors.
    Without {
        /// The sensors left out, by name.
        names: Vec<String>,
        /// Their ids, once registered.
        ids: Vec<SensorId>,
    },
}

impl SensorSelection {
    /// Whether an observation of `sensor`, of kind `kind`, goes into the map.
    #[inline]
    pub fn includes(&self, sensor: SensorId, kind: SensorKind) -> bool {
        match self {
            SensorSelection::All => true,
            SensorSelection::Kinds(k) => k.contains(&kind),
            SensorSelection::Sensors(s) => s.contains(&sensor),
            SensorSelection::Without { ids, .. } => !ids.contains(&sensor),
        }
    }

    /// Every sensor but those named `names` (see [`SensorSelection::Without`]).
    pub fn without(names: Vec<String>) -> Self {
        SensorSelection::Without { names, ids: Vec::new() }
    }

    /// Notes that the sensor `name` was registered as `sensor`.
    fn register(&mut self, sensor: SensorId, name: &str) {
        if let SensorSelection::Without { names, ids } = self {
            let named = |n: &String| name == n || name.strip_prefix(n.as_str()).is_some_and(|r| r.starts_with('@'));
            if names.iter().any(named) {
                ids.push(sensor);
            }
        }
    }
}

/// How an observation is inserted beyond the plain occupancy update.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InsertContext {
    /// Its correlation group, if any.
    pub group: Option<Group>,
    /// The dynamic layer's update at its stamp, if the maps carry one.
    pub dynamic: Option<DynamicUpdate>,
    /// Whether hits on cells holding a dynamic object go to the dynamic layer.
    pub route_hits: bool,
}

/// One map of a [`MapSet`] with its sensor selection and counters.
pub struct MapEntry {
    name: String,
    sensors: SensorSelection,
    grid: FusionGrid,
    stats: InsertStats,
}

impl MapEntry {
    fn new(name: String, sensors: SensorSelection, grid: FusionGrid) -> Self {
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
    pub fn grid(&self) -> &FusionGrid {
        &self.grid
    }

    /// The map, writable.
    pub fn grid_mut(&mut self) -> &mut FusionGrid {
        &mut self.grid
    }

    /// Adds an insertion's counts to the map's.
    pub(super) fn add_stats(&mut self, s: &InsertStats) {
        self.stats.add(s);
    }

    /// Consumes the entry, returning the map.
    pub fn into_grid(self) -> FusionGrid {
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
    /// From how many cell visits a range observation is walked in waves of tiles (see
    /// [`crate::grid::walk_observation_waves`]); `None`: [`crate::grid::waves_threshold`].
    waves_min_cells: Option<u64>,
}

impl MapSet {
    /// A set whose first (primary) map is `grid`, named `name`, taking `sensors`.
    pub fn new(name: impl Into<String>, sensors: SensorSelection, grid: FusionGrid) -> Self {
        Self { primary: MapEntry::new(name.into(), sensors, grid), others: Vec::new(), waves_min_cells: None }
    }

    /// Adds a map and returns its index.
    pub fn add(&mut self, name: impl Into<String>, sensors: SensorSelection, grid: FusionGrid) -> usize {
        self.others.push(MapEntry::new(name.into(), sensors, grid));
        self.others.len()
    }

    /// Adds a map (builder form).
    pub fn with(mut self, name: impl Into<String>, sensors: SensorSelection, grid: FusionGrid) -> Self {
        self.add(name, sensors, grid);
        self
    }

    /// Walks range observations of at least `min_cells` cell visits in waves of tiles
    /// (`u64::MAX`: never; 0: whenever their rays start in one tile); the maps are the same
    /// either way. By default, from [`crate::grid::PARALLEL_MIN_CELLS`] on a pool of two
    /// threads or more.
    pub fn set_waves_min_cells(&mut self, min_cells: u64) {
        self.waves_min_cells = Some(min_cells);
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

    /// The primary map, writable (for a layer written outside the engine's insert paths).
    pub fn primary_mut(&mut self) -> &mut MapEntry {
        &mut self.primary
    }

    /// Notes in every map's selection that the sensor `name` was registered as `sensor`.
    pub(super) fn register(&mut self, sensor: SensorId, name: &str) {
        for m in self.entries_mut() {
            m.sensors.register(sensor, name);
        }
    }

    /// All maps, primary first, writable.
    pub(super) fn entries_mut(&mut self) -> impl Iterator<Item = &mut MapEntry> {
        std::iter::once(&mut self.primary).chain(&mut self.others)
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
    pub fn into_primary(self) -> FusionGrid {
        self.primary.grid
    }

    /// Inserts one observation of a sensor of kind `kind` into every map that takes it.
    /// Returns the summed insertion counts and the number of maps fed.
    pub fn insert(&mut self, kind: SensorKind, data: &RangeData) -> (InsertStats, u64) {
        self.insert_fused(kind, data, &InsertContext::default())
    }

    /// Inserts one observation as a member of a correlation group and/or with the dynamic
    /// layer (see [`FusedUpdate`]).
    pub fn insert_fused(&mut self, kind: SensorKind, data: &RangeData, ctx: &InsertContext) -> (InsertStats, u64) {
        let waves = self.waves_min_cells.unwrap_or_else(crate::grid::waves_threshold);
        let each = self.each_taking(
            |m| m.sensors.includes(data.sensor, kind),
            |m| {
                let s = if ctx.group.is_none() && ctx.dynamic.is_none() {
                    // The plain occupancy update, monomorphised on its own (the common case:
                    // no correlated sensor, no camera).
                    m.grid.insert_in_waves(data, waves)
                } else {
                    let params = m.grid.params();
                    let rule = (&params.pass_through, params.free_threshold);
                    let mut v =
                        FusedUpdate::new(*m.grid.table(), data.evidence, rule, ctx.group, ctx.dynamic, ctx.route_hits);
                    let obs = m.grid.begin_observation();
                    let mut s = m.grid.walk_forked(obs, &data.rays, &mut v, waves);
                    v.finish();
                    s.cell_visits_attenuated += v.attenuated();
                    s.ghost_hits += v.ghost_hits();
                    s.routed_to_dynamic += v.routed;
                    s.dynamic_updates += v.routed;
                    s
                };
                m.stats.add(&s);
                s
            },
        );
        let mut total = InsertStats::default();
        each.iter().for_each(|s| total.add(s));
        (total, each.len() as u64)
    }

    /// Runs `f` on every map for which `takes` is true (those that take an observation)
    /// and returns its results in the maps' order. When several maps take it they are
    /// updated on the pool's threads, one thread per map (see
    /// [`crate::parallel::map_all_mut`]): the maps share no cell and each sees the
    /// observations in the same order, so every map ends bit for bit as on one thread.
    pub(super) fn each_taking<R: Send>(
        &mut self,
        takes: impl Fn(&MapEntry) -> bool,
        f: impl Fn(&mut MapEntry) -> R + Sync + Send,
    ) -> Vec<R> {
        let mut taking: Vec<&mut MapEntry> = self.entries_mut().filter(|m| takes(m)).collect();
        match taking.len() {
            0 | 1 => taking.into_iter().map(f).collect(),
            _ => crate::parallel::map_all_mut(&mut taking, |m| f(m)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_leave_one_out_selection_learns_its_ids_by_name() {
        let grid = || FusionGrid::new(GridGeometry::centered(0.1).unwrap(), OccupancyParams::default());
        let mut maps = MapSet::new("all", SensorSelection::All, grid()).with(
            "without laser",
            SensorSelection::without(vec!["laser".into()]),
            grid(),
        );
        for (i, name) in ["laser", "laser@rear", "laser2", "camera"].iter().enumerate() {
            maps.register(SensorId(i as u16), name);
        }
        let m = maps.by_name("without laser").unwrap().sensors();
        let taken: Vec<bool> = (0..4).map(|i| m.includes(SensorId(i), SensorKind::Lidar)).collect();
        assert_eq!(taken, [false, false, true, true]);
        assert!(maps.primary().sensors().includes(SensorId(0), SensorKind::Lidar));
    }
    use crate::fusion::{Engine, SensorModel};
    use crate::geometry::{PlanarMount, Pose2};
    use crate::grid::{GridGeometry, OccupancyParams, TileKey, TILE_CELLS};
    use crate::measurement::{ObservationId, SensorKind};
    use crate::sensor::{LaserScan, LidarModel, LidarParams, ReturnCounts};
    use crate::sim::SimulatedRun;

    fn grid() -> FusionGrid {
        FusionGrid::new(GridGeometry::centered(0.05).unwrap(), OccupancyParams::default())
    }

    /// Every stored value of a map, as bits, with its tile key.
    fn cells(g: &FusionGrid) -> Vec<(TileKey, Vec<Option<u32>>)> {
        g.tiles().map(|(k, t)| (k, (0..TILE_CELLS).map(|o| t.log_odds(o).map(f32::to_bits)).collect())).collect()
    }

    fn same_map(a: &FusionGrid, b: &FusionGrid) -> bool {
        a.observations() == b.observations() && a.known_box() == b.known_box() && cells(a) == cells(b)
    }

    /// Three sensors seeing the corridor at each instant: a front lidar, a second lidar
    /// with other evidence and a shorter range, and a camera whose range evidence (every
    /// fourth beam, weaker) comes from a model outside the engine.
    struct Rig {
        run: SimulatedRun,
        front: LidarModel,
        rear: LidarModel,
        camera_model: LidarModel,
    }

    const FRONT: SensorId = SensorId(0);
    const REAR: SensorId = SensorId(1);
    const CAMERA: SensorId = SensorId(2);

    impl Rig {
        fn new() -> Self {
            let p = LidarParams::default();
            Rig {
                run: SimulatedRun::document_corridor(),
                front: LidarModel::new(p, PlanarMount::default()),
                rear: LidarModel::new(
                    LidarParams { p_occ: 0.7, p_free: 0.45, max_range: 3.0, ..p },
                    PlanarMount::default(),
                ),
                camera_model: LidarModel::new(LidarParams { p_occ: 0.6, p_free: 0.48, ..p }, PlanarMount::default()),
            }
        }

        fn engine(&self, maps: MapSet) -> Engine {
            let mut e = Engine::with_maps(maps);
            assert_eq!(e.add_lidar("front", self.front), FRONT);
            assert_eq!(e.add_lidar("rear", self.rear), REAR);
            assert_eq!(e.add_sensor("camera", SensorModel::External(SensorKind::Camera)), CAMERA);
            e
        }

        fn camera_data(&self, scan: &LaserScan, pose: Pose2) -> RangeData {
            let sparse = LaserScan {
                stamp: scan.stamp,
                angle_min: scan.angle_min,
                angle_increment: scan.angle_increment * 4.0,
                ranges: scan.ranges.iter().step_by(4).copied().collect(),
            };
            let mut out = RangeData::empty(CAMERA, self.camera_model.evidence());
            self.camera_model.scan_to_range_data(CAMERA, &sparse, pose, &mut out, &mut ReturnCounts::default());
            out
        }

        /// Feeds every observation of the sensors in `only`, in time order, each instant's
        /// observations sharing the instant's id.
        fn feed(&self, e: &mut Engine, only: &[SensorId]) {
            for (i, (scan, pose)) in self.run.scans.iter().zip(&self.run.poses).enumerate() {
                let id = ObservationId(i as u64);
                if only.contains(&FRONT) {
                    e.insert_scan_observed(FRONT, id, scan, f32::NAN, f32::NAN, |_| *pose).unwrap();
                }
                if only.contains(&REAR) {
                    e.insert_scan_observed(REAR, id, scan, f32::NAN, f32::NAN, |_| *pose).unwrap();
                }
                if only.contains(&CAMERA) {
                    e.insert_range_data_observed(id, &self.camera_data(scan, *pose)).unwrap();
                }
            }
        }

        /// A separate single-map run with only the sensors in `only`.
        fn alone(&self, only: &[SensorId]) -> FusionGrid {
            let mut e = self.engine(MapSet::new("alone", SensorSelection::All, grid()));
            self.feed(&mut e, only);
            e.into_grid()
        }
    }

    #[test]
    fn maps_of_one_pass_equal_separate_runs_bit_for_bit() {
        let rig = Rig::new();
        let maps = MapSet::new("M1", SensorSelection::Kinds(vec![SensorKind::Lidar]), grid())
            .with("M2", SensorSelection::Kinds(vec![SensorKind::Camera]), grid())
            .with("M3", SensorSelection::All, grid())
            .with("rear+camera", SensorSelection::Sensors(vec![REAR, CAMERA]), grid());
        let mut e = rig.engine(maps);
        rig.feed(&mut e, &[FRONT, REAR, CAMERA]);
        let maps = e.maps();
        assert_eq!(maps.len(), 4);
        let m1 = rig.alone(&[FRONT, REAR]);
        let m2 = rig.alone(&[CAMERA]);
        let m3 = rig.alone(&[FRONT, REAR, CAMERA]);
        let rc = rig.alone(&[REAR, CAMERA]);
        assert!(same_map(maps.by_name("M1").unwrap().grid(), &m1));
        assert!(same_map(maps.by_name("M2").unwrap().grid(), &m2));
        assert!(same_map(maps.by_name("M3").unwrap().grid(), &m3));
        assert!(same_map(maps.get(3).unwrap().grid(), &rc));
        // The maps do differ from one another, so the equalities above say something.
        assert!(!same_map(&m1, &m3) && !same_map(&m2, &m3) && !same_map(&m1, &rc));
        assert_eq!(maps.by_name("M1").unwrap().grid().observations(), 80);
        assert_eq!(maps.by_name("M2").unwrap().grid().observations(), 40);
        assert_eq!(maps.by_name("M3").unwrap().grid().observations(), 120);
        // The engine's primary map is M1.
        assert!(same_map(e.grid(), &m1));
        // Per-sensor map insertions: front feeds M1 and M3, rear M1, M3 and rear+camera.
        let s: Vec<_> = e.sensor_stats().cloned().collect();
        assert_eq!((s[0].maps_fed, s[1].maps_fed, s[2].maps_fed), (80, 120, 120));
        assert_eq!(s[2].kind, SensorKind::Camera);
        // Per-map counters add up to the engine's.
        let mut sum = crate::grid::InsertStats::default();
        for m in maps.iter() {
            sum.add(m.stats());
        }
        assert_eq!(&sum, &e.stats().insert);
        // The primary map's counters are those of a run that builds it alone (what a
        // summary reports), not the engine's sum over every map.
        let mut alone = rig.engine(MapSet::new("alone", SensorSelection::All, grid()));
        rig.feed(&mut alone, &[FRONT, REAR]);
        assert_eq!(maps.primary().stats(), &alone.stats().insert);
        assert_ne!(maps.primary().stats(), &e.stats().insert);
    }

    #[test]
    fn selection_by_kind_and_by_sensor() {
        let lidar = SensorSelection::Kinds(vec![SensorKind::Lidar]);
        assert!(lidar.includes(SensorId(7), SensorKind::Lidar));
        assert!(!lidar.includes(SensorId(7), SensorKind::Camera));
        let some = SensorSelection::Sensors(vec![SensorId(1)]);
        assert!(some.includes(SensorId(1), SensorKind::Camera));
        assert!(!some.includes(SensorId(2), SensorKind::Lidar));
        assert!(SensorSelection::All.includes(SensorId(9), SensorKind::Camera));
        let set = MapSet::new("a", SensorSelection::All, grid()).with("b", some, grid());
        assert_eq!(set.len(), 2);
        assert!(!set.is_empty());
        assert_eq!(set.get(1).map(|m| m.name()), Some("b"));
        assert!(set.get(2).is_none());
        let names: Vec<_> = set.into_entries().into_iter().map(|m| m.name().to_string()).collect();
        assert_eq!(names, ["a", "b"]);
    }
}
