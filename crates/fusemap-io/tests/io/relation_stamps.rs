//! The SLAM benchmark's relation stamps against the scan stamps of the raw logs they
//! belong to (`shared/datasets/PROVENANCE.md` §3–4), read through fusemap's own readers:
//! how close they are decides the tolerance `fusemap relations` needs. The ROS 1 bags
//! store each CARMEN stamp as seconds + nanoseconds computed from a double, so a relation
//! stamp written with six decimals can differ from its scan's by rounding (tens of ns on
//! Intel); the MIT CSAIL relations are written with five decimals (up to 5 µs off).
//! Skipped without `../shared` (a failure under `FUSEMAP_NO_SKIP=1`).

use fusemap_io::log::{open_log, LogMessage};
use fusemap_io::relations::read_relations;
use fusemap_io::testdata::dataset;

/// The largest distance (ns) from a relation stamp to its nearest scan stamp, with the
/// smallest distance to the second-nearest scan (how much room a tolerance has).
fn stamp_distances(log: &str, relations: &str) -> Option<(u64, u64, usize)> {
    let log = dataset(log)?;
    let relations = read_relations(&dataset(relations)?).unwrap();
    let mut opened = open_log(&log).unwrap();
    let mut scans = Vec::new();
    while let Some(m) = opened.reader.next_message() {
        if let LogMessage::Scan(s) = m.unwrap() {
            scans.push(s.scan.stamp.0);
        }
    }
    scans.sort_unstable();
    let (mut worst, mut room) = (0u64, u64::MAX);
    for t in relations.iter().flat_map(|r| [r.t1.0, r.t2.0]) {
        let i = scans.partition_point(|&s| s < t);
        let mut d: Vec<u64> =
            scans[i.saturating_sub(2)..(i + 2).min(scans.len())].iter().map(|s| s.abs_diff(t)).collect();
        d.sort_unstable();
        worst = worst.max(d[0]);
        room = room.min(d[1]);
    }
    Some((worst, room, scans.len()))
}

#[test]
fn relation_stamps_are_scan_stamps() {
    let cases = [
        ("rosbag1-slam-benchmark/intel.orig.bag", "intel", 1_000),
        ("rosbag1-slam-benchmark/fr079.orig.bag", "fr079", 1_000),
        ("rosbag1-slam-benchmark/aces.orig.bag", "aces", 1_000),
        ("mit-csail-raw/mit-csail.clf", "mit-csail", 10_000),
    ];
    for (log, name, bound_ns) in cases {
        let Some((worst, room, scans)) = stamp_distances(log, &format!("slam-benchmark-relations/{name}.relations"))
        else {
            return;
        };
        eprintln!("{name}: {scans} scans; relation stamp to nearest scan at most {worst} ns, to the next {room} ns");
        assert!(worst <= bound_ns, "{name}: a relation stamp lies {worst} ns from every scan");
        // A 1 ms tolerance cannot pick a wrong scan: the nearest is taken, and the next is far.
        assert!(room > 100 * worst.max(1_000), "{name}: the second-nearest scan is only {room} ns away");
    }
}
