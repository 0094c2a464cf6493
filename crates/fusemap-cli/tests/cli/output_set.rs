//! The output directory holds one complete set: a run that dies half-way through writing
//! (here: killed by a file-size limit, as a full disk would stop it) leaves the previous
//! set whole, the next run cleans up after it, and `summary.json` lists every file of its
//! set with its size and SHA-256.

use crate::util::{assert_success, file_names, read_json, repo_file, run, temp_dir};
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().expect("temp paths are UTF-8")
}

#[test]
fn a_run_killed_while_writing_leaves_the_old_set_and_is_cleaned_up() {
    let dir = temp_dir("output-set");
    let out = dir.join("out");
    let world = repo_file("worlds/corridor.toml");
    assert_success(&run(&["map", "--world", s(&world), "--out", s(&out)]));
    let before: Vec<(String, Vec<u8>)> = file_names(&out)
        .into_iter()
        .filter(|n| !n.starts_with('.'))
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect();
    assert!(before.iter().any(|(n, _)| n == "map.pgm") && before.iter().any(|(n, _)| n == "summary.json"));

    // The summary lists the other files of its set, and they match.
    let summary = read_json(&out.join("summary.json"));
    let listed = summary["files"].as_array().unwrap();
    assert_eq!(listed.len(), before.len() - 1, "{listed:?}");
    for f in listed {
        let name = f["name"].as_str().unwrap();
        let (bytes, sha) = fusemap_io::output_set::digest(&out.join(name)).unwrap();
        assert_eq!(f["bytes"].as_u64(), Some(bytes), "{name}");
        assert_eq!(f["sha256"].as_str(), Some(sha.as_str()), "{name}");
    }

    // A second run of another map into the same directory, stopped by a 16-block file-size
    // limit while it writes its map (SIGXFSZ or EFBIG, as a full disk would stop it).
    let finer = dir.join("finer.toml");
    std::fs::write(&finer, "[map]\nresolution = 0.02\n").unwrap();
    let script = format!(
        "ulimit -f 16; exec '{}' map --config '{}' --world '{}' --out '{}'",
        env!("CARGO_BIN_EXE_fusemap"),
        s(&finer),
        s(&world),
        s(&out)
    );
    let o = std::process::Command::new("sh").args(["-c", &script]).output().unwrap();
    assert!(!o.status.success(), "the limited run succeeded");
    for (name, bytes) in &before {
        assert!(std::fs::read(out.join(name)).unwrap() == *bytes, "{name} changed by the failed run");
    }
    assert!(!file_names(&out).iter().any(|n| !n.starts_with('.') && !before.iter().any(|(b, _)| b == n)));

    // The next run goes ahead (the dead run's lock died with it) and leaves no staging.
    assert_success(&run(&["map", "--config", s(&finer), "--world", s(&world), "--out", s(&out)]));
    let names = file_names(&out);
    assert!(!names.iter().any(|n| n.starts_with(".fusemap-staging")), "{names:?}");
    assert!(std::fs::read(out.join("map.pgm")).unwrap() != before.iter().find(|(n, _)| n == "map.pgm").unwrap().1);
    std::fs::remove_dir_all(&dir).unwrap();
}
