//! Which observations are correlated: the configured groups of sensors whose
//! observations within a time window are one look at the world (a lidar scan and the
//! camera frame taken with it; two outputs of one pre-processing step), and the group
//! number each observation gets.
//!
//! The merge itself happens per cell in the map ([`Group`]); this only decides
//! membership: an observation of a grouped sensor joins the group's open instance when it
//! lies within `window` of the instance's first observation and its sensor has not
//! contributed yet; otherwise it opens a new instance. A sensor contributes at most one
//! observation per instance, so two scans of one lidar are never merged with each other.

use crate::grid::{Group, MergeRule};
use crate::measurement::SensorId;
use crate::time::Stamp;

/// The correlation settings of an engine.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Correlation {
    /// Groups of sensors whose observations within `window_ns` are merged.
    pub groups: Vec<Vec<SensorId>>,
    /// The window, nanoseconds.
    pub window_ns: i64,
    /// How the members' evidence is combined.
    pub rule: MergeRule,
}

/// One open instance of a group.
#[derive(Clone, Debug)]
struct Open {
    id: u64,
    start: Stamp,
    members: Vec<SensorId>,
}

/// Assigns group numbers as observations arrive in time order.
#[derive(Clone, Debug, Default)]
pub(super) struct Correlator {
    cfg: Correlation,
    open: Vec<Option<Open>>,
    next: u64,
    /// Observations that joined an instance another observation had opened.
    pub(super) merged: u64,
}

impl Correlator {
    pub(super) fn new(cfg: Correlation) -> Self {
        let open = vec![None; cfg.groups.len()];
        Self { cfg, open, next: 1, merged: 0 }
    }

    /// True when no sensors are declared correlated.
    pub(super) fn is_empty(&self) -> bool {
        self.cfg.groups.is_empty()
    }

    /// The group an observation of `sensor` at `stamp` belongs to, `None` for a sensor in
    /// no configured group.
    pub(super) fn assign(&mut self, sensor: SensorId, stamp: Stamp) -> Option<Group> {
        let gi = self.cfg.groups.iter().position(|g| g.contains(&sensor))?;
        let rule = self.cfg.rule;
        if let Some(o) = self.open[gi].as_mut() {
            if stamp.0.saturating_sub(o.start.0) <= self.cfg.window_ns && !o.members.contains(&sensor) {
                o.members.push(sensor);
                self.merged += 1;
                return Some(Group { id: o.id, rule });
            }
        }
        let id = self.next;
        self.next += 1;
        self.open[gi] = Some(Open { id, start: stamp, members: vec![sensor] });
        Some(Group { id, rule })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn members_within_the_window_share_a_group_once_per_sensor() {
        let (lidar, camera, other) = (SensorId(0), SensorId(1), SensorId(2));
        let mut c = Correlator::new(Correlation {
            groups: vec![vec![lidar, camera]],
            window_ns: 50_000_000,
            rule: MergeRule::Max,
        });
        let a = c.assign(lidar, Stamp(0)).unwrap();
        assert_eq!(c.assign(camera, Stamp(30_000_000)).unwrap(), a);
        // The same lidar again: a new instance, even inside the window.
        let b = c.assign(lidar, Stamp(40_000_000)).unwrap();
        assert_ne!(a, b);
        // Beyond the window: a new instance.
        let d = c.assign(camera, Stamp(100_000_000)).unwrap();
        assert_ne!(b, d);
        assert_eq!(c.assign(other, Stamp(100_000_000)), None);
        assert_eq!(c.merged, 1);
    }
}
