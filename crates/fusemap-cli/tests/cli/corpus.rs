//! The committed bad-input corpus (`tests/corpus`): `make_corpus.py` writes its cases
//! (broken, hostile and unusual CARMEN logs, ROS 1 bags, MCAP files, rosbag2 directories,
//! config and world files, output directories and command lines) and `run_corpus.py`
//! runs each through `fusemap map` and `fusemap doctor` under a 1 GiB address-space
//! limit and a time limit, checking its expected outcome, that nothing crashed, hung or
//! peaked past 1 GiB, and that no input was touched. See docs/RELIABILITY.md.

use crate::util::{python, python_with, repo_file, stderr, stdout, temp_dir};

#[test]
fn every_case_of_the_bad_input_corpus_gives_its_expected_outcome() {
    if !python_with(&["rosbags", "mcap", "zstandard"]) {
        return;
    }
    let dir = temp_dir("corpus");
    let cases = dir.join("cases");
    let made = python().arg(repo_file("tests/corpus/make_corpus.py")).arg(&cases).output().expect("python runs");
    assert!(made.status.success(), "make_corpus.py failed:\n{}{}", stdout(&made), stderr(&made));
    let ran = python()
        .arg(repo_file("tests/corpus/run_corpus.py"))
        .arg("--fusemap")
        .arg(env!("CARGO_BIN_EXE_fusemap"))
        .arg(&cases)
        .output()
        .expect("python runs");
    println!("{}", stdout(&ran));
    assert!(ran.status.success(), "corpus failures:\n{}{}", stdout(&ran), stderr(&ran));
    std::fs::remove_dir_all(&dir).unwrap();
}
