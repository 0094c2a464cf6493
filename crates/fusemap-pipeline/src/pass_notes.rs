//! The notes a mapping pass leaves about its lidars: contradictory stamps, skipped scans
//! and why.

use crate::insert::Mapped;
use crate::sync::Skipped;
use fusemap_core::config::LogConfig;

/// A lidar's contradictory stamps: all scans at one stamp, or scans sharing the stamp of
/// the scan before them with other ranges (a repeat, same ranges, has its own note).
fn stamp_notes(r: &crate::report::LidarReport, notes: &mut Vec<String>) {
    let (n, shared) = (r.timing.count, r.timing.duplicates);
    if n > 2 && shared + 1 == n {
        notes.push(format!(
            "every one of the {n} scans of `{}` carries the same header stamp: where the scans carry no pose of \
             their own, each is placed at the pose of that one instant",
            r.topic
        ));
    } else if shared > r.scans_skipped.repeated {
        notes.push(format!(
            "{} scans of `{}` carry the stamp of the scan before them but other ranges (two scans at one \
             instant: a second lidar on the topic, or a driver's stamping fault); both are placed at that \
             instant's pose",
            shared - r.scans_skipped.repeated,
            r.topic
        ));
    }
}

/// The lidars' notes (stamps going backwards, refused, repeated, late and unposed scans);
/// the skipped scans of all of them.
pub(crate) fn lidar_notes(lidars: &[Mapped], cfg: &LogConfig, notes: &mut Vec<String>) -> Skipped {
    let mut skipped = Skipped::default();
    for l in lidars {
        let r = &l.report;
        skipped.add(&r.scans_skipped);
        if r.timing.regressions > 0 {
            let order = if r.scans_reordered > 0 {
                format!(": {} scans mapped in stamp order", r.scans_reordered)
            } else {
                String::new()
            };
            notes.push(format!("`{}` stamps go backwards {} times{order}", r.topic, r.timing.regressions));
        }
        stamp_notes(r, notes);
        if r.scans_skipped.bad_angles > 0 {
            notes.push(format!(
                "{} scans of `{}` refused: their beam angles cannot be placed (first: {})",
                r.scans_skipped.bad_angles,
                r.topic,
                l.bad_angles_example.as_deref().unwrap_or("?")
            ));
        }
        if r.scans_skipped.repeated > 0 {
            notes.push(format!(
                "{} scans of `{}` repeat the scan before them (same stamp, same ranges): each was inserted once",
                r.scans_skipped.repeated, r.topic
            ));
        }
        if r.scans_skipped.frozen > 0 {
            notes.push(format!(
                "{} scans of `{}` are frozen: the ranges of the scan before, bit for bit, while the pose track moved (a driver republishing its last reading); they were not mapped",
                r.scans_skipped.frozen, r.topic
            ));
        }
        if r.scans_skipped.late > 0 {
            notes.push(format!(
                "{} scans of `{}` arrived more than log.reorder_window_s = {} s behind the others and were dropped",
                r.scans_skipped.late, r.topic, cfg.reorder_window_s
            ));
        }
    }
    let read: u64 = lidars.iter().map(|l| l.report.scans_read).sum();
    let without_pose = skipped.total() - skipped.bad_angles - skipped.repeated - skipped.frozen;
    if without_pose > 0 {
        notes.push(format!("{without_pose} of {read} scans skipped without a pose"));
    }
    skipped
}
