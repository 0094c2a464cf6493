//! Insertion throughput on the corridor (workload a) and a slice of workload c.
//! `cargo bench -p fusemap-core`. The full workloads with memory figures are
//! `fusemap bench`.

use fusemap_core::fusion::Engine;
use fusemap_core::geometry::PlanarMount;
use fusemap_core::grid::{FusionGrid, GridGeometry, OccupancyParams};
use fusemap_core::sensor::LidarModel;
use fusemap_core::sim::{workload, Workload};
use std::sync::OnceLock;

fn main() {
    divan::main();
}

fn map_all(w: &Workload, scans: usize) -> u64 {
    let grid = FusionGrid::new(GridGeometry::centered(w.resolution).unwrap(), OccupancyParams::default());
    let mut e = Engine::new(grid);
    let id = e.add_lidar("laser", LidarModel::new(w.lidar, PlanarMount::default()));
    for (s, p) in w.run.scans.iter().zip(&w.run.poses).take(scans) {
        e.insert_scan(id, s, *p).unwrap();
    }
    e.stats().insert.cell_visits
}

#[divan::bench]
fn corridor_a(bencher: divan::Bencher) {
    static W: OnceLock<Workload> = OnceLock::new();
    let w = W.get_or_init(|| workload('a').unwrap());
    bencher.counter(divan::counter::ItemsCount::new(40usize * 181)).bench(|| map_all(w, 40));
}

#[divan::bench]
fn box_c_first_200_scans(bencher: divan::Bencher) {
    static W: OnceLock<Workload> = OnceLock::new();
    let w = W.get_or_init(|| workload('c').unwrap());
    bencher.counter(divan::counter::ItemsCount::new(200usize * 1081)).bench(|| map_all(w, 200));
}
