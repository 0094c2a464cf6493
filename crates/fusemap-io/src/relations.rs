//! Relations files of the SLAM benchmark (Kümmerle et al. 2009, "On measuring the accuracy
//! of SLAM algorithms"): `t1 t2 x y z roll pitch yaw` a line, the true relative motion
//! between the robot poses at two scan stamps. The format and the metric live in
//! [`fusemap_core::metrics`]; this module reads the file and names it in errors.

use crate::input_file::read_text_within;
use crate::{Error, Location, Result};
use fusemap_core::metrics::{parse_relations, Relation};
use std::path::Path;

/// The largest relations file read, bytes (256 MiB). The benchmark's largest file
/// (MIT Killian Court, 4,677 relations) is 0.4 MB; a file a thousand times larger is not a
/// relations file, and reading it whole would only exhaust memory.
pub const MAX_RELATIONS_BYTES: u64 = 256 << 20;

/// Reads and parses a relations file. Errors name the file and, for content, the line
/// and what was wrong; a file over [`MAX_RELATIONS_BYTES`] or without a single relation
/// is refused.
pub fn read_relations(path: &Path) -> Result<Vec<Relation>> {
    let text = read_text_within(path, MAX_RELATIONS_BYTES, "a relations file")?;
    let relations =
        parse_relations(&text).map_err(|e| Error::format(path, Location::Line(e.line as u64), e.message))?;
    if relations.is_empty() {
        return Err(Error::format(path, Location::File, "no relations (lines `t1 t2 x y z roll pitch yaw`)"));
    }
    Ok(relations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testdata::{dataset, temp_dir};

    #[test]
    fn errors_name_the_file_and_the_line() {
        let dir = temp_dir("relations");
        let p = dir.join("bad.relations");
        std::fs::write(&p, "1.0 2.0 0.1 0.2 0 0 0 0.3\n# note\n1.0 2.0 0.1 0.2 0 0 0\n").unwrap();
        let e = read_relations(&p).unwrap_err().to_string();
        assert!(e.starts_with(&p.display().to_string()) && e.contains(":3: expected 8 fields"), "{e}");

        std::fs::write(&p, "# nothing\n\n").unwrap();
        let e = read_relations(&p).unwrap_err().to_string();
        assert!(e.contains("bad.relations") && e.contains("no relations"), "{e}");

        std::fs::write(&p, b"1.0 2.0 0.1 0.2 0 0 0 0.3\n1.0 2.0 \xff\n").unwrap();
        let e = read_relations(&p).unwrap_err().to_string();
        assert!(e.contains(":2: the file is not valid UTF-8"), "{e}");

        let missing = dir.join("missing.relations");
        assert!(read_relations(&missing).unwrap_err().to_string().contains("missing.relations"));

        std::fs::write(&p, "1.5 2.25 0.1 0.2 0 0 0 0.3\n").unwrap();
        let r = read_relations(&p).unwrap();
        assert_eq!((r.len(), r[0].line, r[0].t2.0), (1, 1, 2_250_000_000));
    }

    #[test]
    fn refuses_a_file_over_the_limit() {
        let dir = temp_dir("relations-big");
        let p = dir.join("huge.relations");
        let f = std::fs::File::create(&p).unwrap();
        // Sparse: no disk space used.
        f.set_len(MAX_RELATIONS_BYTES + 1).unwrap();
        let e = read_relations(&p).unwrap_err().to_string();
        assert!(e.contains("huge.relations") && e.contains("larger than 256 MiB"), "{e}");
    }

    /// Every relations file of the benchmark parses, with the relation counts of
    /// `shared/datasets/PROVENANCE.md` §3, two distinct stamps per relation and finite
    /// motions.
    #[test]
    fn the_benchmark_files_parse() {
        let files = [("intel", 2984), ("fr079", 1685), ("aces", 1279), ("mit-csail", 1172), ("mit-killian", 4677)];
        for (name, count) in files {
            let Some(p) = dataset(&format!("slam-benchmark-relations/{name}.relations")) else { return };
            let r = read_relations(&p).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(r.len(), count, "{name}");
            assert!(r.iter().all(|r| r.t1 != r.t2), "{name}: a relation from a pose to itself");
            assert!(r.iter().all(|r| r.motion.is_finite() && r.motion.theta.abs() <= std::f64::consts::PI));
        }
    }
}
