//! Tests of the CARMEN reader.

use super::*;
use std::io::Write;

fn reader(text: &str, options: CarmenOptions) -> CarmenReader<&[u8]> {
    CarmenReader::from_reader("test.log", text.as_bytes(), options).unwrap()
}

/// All messages of a log read leniently, with the stats.
fn read_all(text: &str) -> (Vec<LogMessage>, ReadStats) {
    let mut r = reader(text, CarmenOptions::default());
    let messages = r.by_ref().map(|m| m.unwrap()).collect();
    (messages, r.stats().clone())
}

fn scan(m: &LogMessage) -> &ScanMessage {
    match m {
        LogMessage::Scan(s) => s,
        other => panic!("not a scan: {other:?}"),
    }
}

/// A FLASER line with the given ranges.
fn flaser_line(ranges: &[&str]) -> String {
    format!("FLASER {} {} 1.5 -2.25 0.5 1.0 -2.0 0.25 1134864629.895182 b21 0.086295\n", ranges.len(), ranges.join(" "))
}

fn flaser_n(n: usize) -> String {
    flaser_line(&vec!["1.0"; n])
}

fn last_angle(s: &ScanMessage) -> f64 {
    s.scan.angle_min + s.scan.angle_increment * (s.scan.ranges.len() - 1) as f64
}

#[test]
fn flaser_fields() {
    let (m, stats) = read_all(&flaser_line(&["1.25", "2.5", "81.83"]));
    assert_eq!(m.len(), 1);
    let s = scan(&m[0]);
    assert_eq!(s.topic, "FLASER");
    assert_eq!(s.frame_id, "");
    assert_eq!(s.scan.stamp, Stamp(1_134_864_629_895_182_000));
    assert_eq!(s.receive_stamp, Some(Stamp(86_295_000)));
    assert_eq!(s.scan.ranges, vec![1.25, 2.5, 81.83]);
    assert_eq!(s.pose, Some(Pose2::new(1.5, -2.25, 0.5)));
    assert_eq!(s.odom_pose, Some(Pose2::new(1.0, -2.0, 0.25)));
    assert_eq!(s.laser_pose, None);
    assert_eq!((s.time_increment, s.scan_time, s.range_min), (0.0, 0.0, 0.0));
    assert_eq!(s.range_max, 81.0);
    assert_eq!(stats, ReadStats::default());
}

#[test]
fn rlaser_reads_like_flaser() {
    let (m, _) = read_all(&flaser_n(180).replacen("FLASER", "RLASER", 1));
    let s = scan(&m[0]);
    assert_eq!(s.topic, "RLASER");
    assert_eq!(s.scan.ranges.len(), 180);
    assert_eq!(s.pose, Some(Pose2::new(1.5, -2.25, 0.5)));
}

#[test]
fn flaser_angle_rules() {
    let deg = PI / 180.0;
    // (n, first, step, last)
    let cases = [
        (180, -90.0, 1.0, 89.0),
        (181, -90.0, 1.0, 90.0),
        (360, -90.0, 0.5, 89.5),
        (361, -90.0, 0.5, 90.0),
        (5, -90.0, 45.0, 90.0),
        (91, -90.0, 2.0, 90.0),
    ];
    for (n, first, step, last) in cases {
        let (m, _) = read_all(&flaser_n(n));
        let s = scan(&m[0]);
        assert_eq!(s.scan.ranges.len(), n);
        assert!((s.scan.angle_min - first * deg).abs() < 1e-12, "n={n}");
        assert!((s.scan.angle_increment - step * deg).abs() < 1e-12, "n={n}");
        assert!((last_angle(s) - last * deg).abs() < 1e-9, "n={n}");
    }
    assert_eq!(flaser_angles(1), (0.0, 0.0));
    assert_eq!(flaser_angles(0), (0.0, 0.0));
}

#[test]
fn flaser_no_return_rule() {
    let range_max = |ranges: &[&str], options: CarmenOptions| {
        let line = flaser_line(ranges);
        let mut r = reader(&line, options);
        scan(&r.next().unwrap().unwrap()).range_max
    };
    let lenient = CarmenOptions::default();
    // 50 m-mode logs: sentinels 50.0 and up to ≈51.25.
    assert_eq!(range_max(&["3.0", "50.0"], lenient), 50.0);
    assert_eq!(range_max(&["3.0", "51.25"], lenient), 50.0);
    // 80 m-mode logs: sentinels 81.83 / 81.91.
    assert_eq!(range_max(&["3.0", "81.91"], lenient), 81.0);
    assert_eq!(range_max(&["3.0", "51.6"], lenient), 81.0);
    // 16-bit millimetre overflow (Örebro): 32.759–32.767 is no return.
    assert_eq!(range_max(&["3.0", "32.767"], lenient), 32.7);
    assert_eq!(range_max(&["3.0", "32.6"], lenient), 50.0);
    assert_eq!(range_max(&["3.0", "32.8", "32.767"], lenient), 50.0);
    // Only finite values count: an inf must not make 50 m sentinels into hits.
    assert_eq!(range_max(&["inf", "50.0"], lenient), 50.0);
    let fixed = CarmenOptions { flaser_range_max: Some(32.7), ..lenient };
    assert_eq!(range_max(&["3.0", "32.767"], fixed), 32.7);
}

#[test]
fn nan_and_inf_ranges_are_kept() {
    let (m, stats) = read_all(&flaser_line(&["nan", "inf", "-inf", "NaN", "0", "-1"]));
    let r = &scan(&m[0]).scan.ranges;
    assert!(r[0].is_nan() && r[3].is_nan());
    assert_eq!(&r[1..3], &[f32::INFINITY, f32::NEG_INFINITY]);
    assert_eq!(&r[4..], &[0.0, -1.0]);
    assert_eq!(stats.malformed, 0);
}

#[test]
#[allow(clippy::approx_constant)] // -1.570796 is the rounded start angle the log writes
fn robotlaser1_fields() {
    let line = "ROBOTLASER1 0 -1.570796 3.150447 0.008727 80.000000 0.010000 0 3 \
                4.04 81.91 nan 2 0.5 0.7 \
                1.0 2.0 0.1 0.9 1.9 0.2 0.3 0.05 0.5 0.4 1 \
                1134864642.914187 b21 0.430003\n";
    let (m, stats) = read_all(line);
    assert_eq!(stats.malformed, 0, "{stats:?}");
    let s = scan(&m[0]);
    assert_eq!(s.topic, "ROBOTLASER1");
    assert_eq!(s.scan.angle_min, -1.570796);
    assert_eq!(s.scan.angle_increment, 0.008727);
    assert_eq!(s.scan.ranges.len(), 3);
    assert_eq!(s.range_max, 80.0);
    assert_eq!(s.laser_pose, Some(Pose2::new(1.0, 2.0, 0.1)));
    assert_eq!(s.pose, Some(Pose2::new(0.9, 1.9, 0.2)));
    assert_eq!(s.odom_pose, None);
    assert_eq!(s.scan.stamp, Stamp(1_134_864_642_914_187_000));
    assert_eq!(s.receive_stamp, Some(Stamp(430_003_000)));
}

#[test]
fn rawlaser_fields() {
    for k in 1..=4 {
        let line = format!("RAWLASER{k} 0 -1.5 3.0 0.75 30.0 0.01 0 5 1 2 3 4 30 0 12.5 host 12.75\n");
        let (m, stats) = read_all(&line);
        assert_eq!(stats.malformed, 0, "{stats:?}");
        let s = scan(&m[0]);
        assert_eq!(s.topic, format!("RAWLASER{k}"));
        assert_eq!((s.scan.angle_min, s.scan.angle_increment), (-1.5, 0.75));
        assert_eq!(s.scan.ranges, vec![1.0, 2.0, 3.0, 4.0, 30.0]);
        assert_eq!(s.range_max, 30.0);
        assert_eq!((s.pose, s.odom_pose, s.laser_pose), (None, None, None));
        assert_eq!(s.scan.stamp, Stamp(12_500_000_000));
        assert_eq!(s.receive_stamp, Some(Stamp(12_750_000_000)));
    }
    // No maximum_range on the line: the FLASER rule.
    let (m, _) = read_all("RAWLASER1 0 -1.5 3.0 1.5 0 0.01 0 3 1 81.91 2 1 7 1 h 1\n");
    assert_eq!(scan(&m[0]).range_max, 81.0);
}

#[test]
fn odom_fields() {
    let (m, _) = read_all("ODOM 0.600266 -0.0320327 -0.354665 0.1 0.2 0 -0.042 pippo 0\n");
    let LogMessage::Odometry(o) = &m[0] else { panic!("not odometry") };
    assert_eq!(o.topic, "ODOM");
    assert_eq!((o.frame_id.as_str(), o.child_frame_id.as_str()), ("odom", "base_link"));
    assert_eq!(o.pose, Pose2::new(0.600266, -0.0320327, -0.354665));
    assert_eq!(o.stamp, Stamp(-42_000_000));
    assert_eq!(o.receive_stamp, Some(Stamp(0)));
}

#[test]
fn params_comments_blank_and_unknown_types() {
    let log = "# message formats defined: PARAM SYNC ODOM FLASER\n\
               ## another comment\n\
               \n   \t\r\n\
               #PARAM simulator_num_readings 181 nohost 0\n\
               PARAM robot_front_laser_max 80.99 1071078718.462518 merci 1071078718.462517\n\
               PARAM robot_use_laser on nohost 0\n\
               NEFF 15\n\
               TRUEPOS 1 2 3 4 5 6 7 h 7\n\
               NEFF 16\n\
               ODOM 0 0 0 0 0 0 0 pippo 0\r\n";
    let mut r = reader(log, CarmenOptions::default());
    let m: Vec<_> = r.by_ref().map(|m| m.unwrap()).collect();
    assert_eq!(m.len(), 1);
    assert_eq!(r.param("robot_front_laser_max"), Some("80.99"));
    assert_eq!(r.param("robot_use_laser"), Some("on"));
    assert_eq!(r.param("simulator_num_readings"), None);
    assert_eq!(r.params().len(), 2);
    let skipped = &r.stats().skipped_by_type;
    assert_eq!(skipped.get("NEFF"), Some(&2));
    assert_eq!(skipped.get("TRUEPOS"), Some(&1));
    assert_eq!(skipped.len(), 2);
    assert_eq!(r.stats().malformed, 0);
    assert_eq!(r.line_number(), 11);
}

/// Line 1 good, then one malformed line of each kind, then a good line.
fn malformed_log() -> Vec<u8> {
    let mut log = flaser_n(3).into_bytes();
    log.extend_from_slice(b"FLASER 180 1 2 3 0 0 0 0 0 0 1 h 1\n"); // 2: too few
    log.extend_from_slice(b"FLASER 2 1.0 abc 0 0 0 0 0 0 1 h 1\n"); // 3: garbage
    log.extend_from_slice(b"FLASER 2 1.0 2.0 nan 0 0 0 0 0 1 h 1\n"); // 4: NaN pose
    log.extend_from_slice(b"ODOM 0 0 0 0 0 0 1.2.3 h 1\n"); // 5: bad stamp
    log.extend_from_slice(b"ODOM 0 0 0 0 0 0 1 h\n"); // 6: too few
    log.extend_from_slice(b"FLASER 2 1.0 2.0 0 0 \xff\xfe 0 0 0 1 h 1\n"); // 7: not UTF-8
    log.extend_from_slice(b"3.5 garbage line\n"); // 8: not a message
    log.extend_from_slice(b"FLASER -3 1 2 3\n"); // 9: bad count
    log.extend_from_slice(b"PARAM lonely\n"); // 10: no value
    log.extend_from_slice(b"ROBOTLASER1 0 0 0 0.1 80 0 0 2 1 2 5 1 2\n"); // 11: count does not fit
    log.extend_from_slice(b"ODOM 1 2 3 0 0 0 7 h 7\n"); // 12: good
    log
}

#[test]
fn malformed_lines_are_counted_with_their_line() {
    let log = malformed_log();
    let mut r = CarmenReader::from_reader("intel.log", &log[..], CarmenOptions::default()).unwrap();
    let m: Vec<_> = r.by_ref().map(|m| m.unwrap()).collect();
    assert_eq!(m.len(), 2);
    let stats = r.stats();
    assert_eq!(stats.malformed, 10);
    let lines: Vec<&str> = stats.malformed_examples.iter().map(|d| d.split(": ").next().unwrap()).collect();
    let expected: Vec<String> = (2..=11).map(|l| format!("intel.log:{l}")).collect();
    assert_eq!(lines, expected);
    let ex = &stats.malformed_examples;
    assert_eq!(ex[0], "intel.log:2: FLASER: expected 191 fields for 180 readings, found 14");
    assert!(ex[1].contains("field 4 (range reading): `abc` is not a number"), "{}", ex[1]);
    assert!(ex[2].contains("field 5 (x): `nan` is not a finite number"), "{}", ex[2]);
    assert!(ex[3].contains("ODOM: field 8 (ipc_timestamp)"), "{}", ex[3]);
    assert!(ex[4].contains("ODOM: expected 10 fields"), "{}", ex[4]);
    assert!(ex[5].contains("not UTF-8"), "{}", ex[5]);
    assert!(ex[6].contains("not a CARMEN message"), "{}", ex[6]);
    assert!(ex[7].contains("`-3` is not a count"), "{}", ex[7]);
    assert!(ex[8].contains("PARAM: the line ends"), "{}", ex[8]);
    assert!(ex[9].contains("ROBOTLASER1:"), "{}", ex[9]);
    assert!(stats.skipped_by_type.is_empty());
}

#[test]
fn strict_mode_returns_format_errors_and_goes_on() {
    let log = malformed_log();
    let strict = CarmenOptions { strict: true, ..Default::default() };
    let r = CarmenReader::from_reader("intel.log", &log[..], strict).unwrap();
    let items: Vec<_> = r.collect();
    assert_eq!(items.len(), 12);
    assert!(items[0].is_ok() && items[11].is_ok());
    for (i, item) in items[1..11].iter().enumerate() {
        match item {
            Err(Error::Format { path, location: Location::Line(l), .. }) => {
                assert_eq!(path, Path::new("intel.log"));
                assert_eq!(*l, i as u64 + 2);
            }
            other => panic!("line {}: {other:?}", i + 2),
        }
    }
    let err = items[3].as_ref().unwrap_err().to_string();
    assert_eq!(err, "intel.log:4: FLASER: field 5 (x): `nan` is not a finite number");
}

#[test]
fn stamps_are_exact() {
    assert_eq!(parse_stamp("1134864629.895182"), Some(Stamp(1_134_864_629_895_182_000)));
    assert_eq!(parse_stamp("-0.042"), Some(Stamp(-42_000_000)));
    assert_eq!(parse_stamp("1.13486e+09"), Some(Stamp(1_134_860_000_000_000_000)));
    assert_eq!(parse_stamp("4.29497e+09"), Some(Stamp(4_294_970_000_000_000_000)));
    assert_eq!(parse_stamp("1.5E-3"), Some(Stamp(1_500_000)));
    assert_eq!(parse_stamp("-2.5e1"), Some(Stamp(-25_000_000_000)));
    assert_eq!(parse_stamp("12e0"), Some(Stamp(12_000_000_000)));
    assert_eq!(parse_stamp("1.234567891234e2"), Some(Stamp(123_456_789_123)));
    // Garbage denormals in some corrected logs: below a nanosecond, so 0.
    assert_eq!(parse_stamp("6.53023e-43"), Some(Stamp(0)));
    assert_eq!(parse_stamp("5.29905e-312"), Some(Stamp(0)));
    assert_eq!(parse_stamp("-1.5e-9"), Some(Stamp(-1)));
    assert_eq!(parse_stamp("1.5e-10"), Some(Stamp(0)));
    for bad in ["", "e5", "1e", "1e+", "1.2.3e1", "nan", "inf", "1e99", "0x1p3", "1e5e5", "-e1", ".e1"] {
        assert_eq!(parse_stamp(bad), None, "{bad}");
    }
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

#[test]
fn gzip_is_recognised_by_content() {
    let text = format!("{}ODOM 0 0 0 0 0 0 1 h 1\n", flaser_n(181));
    // Two members, as `cat a.gz b.gz` makes them.
    let mut gz = gzip(text.as_bytes());
    gz.extend(gzip(text.as_bytes()));
    let r = CarmenReader::from_reader("x.log", &gz[..], CarmenOptions::default()).unwrap();
    let m: Vec<_> = r.map(|m| m.unwrap()).collect();
    assert_eq!(m.len(), 4);
    assert_eq!(scan(&m[2]).scan.ranges.len(), 181);

    // Cut short: an error naming the file and the last whole line, then the end.
    let cut = &gz[..gz.len() / 2 - 10];
    let mut r = CarmenReader::from_reader("x.log.gz", cut, CarmenOptions::default()).unwrap();
    let mut items: Vec<_> = r.by_ref().collect();
    let last = items.pop().unwrap().unwrap_err();
    assert!(items.iter().all(|i| i.is_ok()));
    let Error::Truncated { path, location: Location::File, message } = &last else { panic!("{last:?}") };
    assert_eq!(path, Path::new("x.log.gz"));
    assert!(message.starts_with("gzip stream ends early after line"), "{message}");
    assert!(r.next().is_none());
}

#[test]
fn sniff_recognises_carmen_by_content() {
    let log = format!("# message formats defined: PARAM ODOM FLASER\n{}", flaser_n(180));
    assert!(sniff(log.as_bytes()));
    assert!(sniff(&gzip(log.as_bytes())));
    // Only part of a gzip stream, as a caller reading the first KiB passes it.
    let ranges: Vec<String> = (0..20_000u64).map(|i| format!("{:.3}", (i * 7919 % 10007) as f64 / 300.0)).collect();
    let ranges: Vec<&str> = ranges.iter().map(String::as_str).collect();
    let big = gzip(format!("{log}{}", flaser_line(&ranges)).as_bytes());
    assert!(big.len() > 4096);
    assert!(sniff(&big[..1024]));
    assert!(sniff(b"ODOM 0 0 0 0 0 0 0 pippo 0\nODOM"));
    assert!(sniff(b"##  (ODOM, FLASER, PARAM)\n## message formats defined: PARAM\n"));
    assert!(sniff(b"\n\nROBOTLASER1 0 -1.570796"));
    assert!(sniff(b"NEFF 15\n"));
    assert!(!sniff(b"#ROSBAG V2.0\nE\x00\x00\x00"));
    assert!(!sniff(b"# just a comment\n"));
    assert!(!sniff(b"x: 1\ny: 2\n"));
    assert!(!sniff(b"FLASERX 1 2\n"));
    assert!(!sniff(b"\x89PNG\r\n\x1a\n"));
    assert!(!sniff(b""));
    assert!(!sniff(b"\x1f\x8b"));
    // The first token cut off by the end of the bytes: undecided, so no.
    assert!(!sniff(b"FLAS"));
}

// ---- The shared CARMEN data (counts as measured in PROVENANCE.md). ----

#[derive(Debug, Default)]
struct Summary {
    by_topic: BTreeMap<String, u64>,
    beams: BTreeMap<usize, u64>,
    first_scan: Option<ScanMessage>,
    first_odom: Option<OdomMessage>,
    pose_is_odom: bool,
    stats: ReadStats,
    params: BTreeMap<String, String>,
}

fn summarise(relative: &str) -> Option<Summary> {
    let path = crate::testdata::dataset(relative)?;
    let mut r = CarmenReader::open(&path, CarmenOptions::default()).unwrap();
    let mut s = Summary { pose_is_odom: true, ..Default::default() };
    for m in r.by_ref() {
        match m.unwrap() {
            LogMessage::Scan(scan) => {
                *s.by_topic.entry(scan.topic.clone()).or_default() += 1;
                *s.beams.entry(scan.scan.ranges.len()).or_default() += 1;
                s.pose_is_odom &= scan.pose == scan.odom_pose;
                s.first_scan.get_or_insert(scan);
            }
            LogMessage::Odometry(odom) => {
                *s.by_topic.entry(odom.topic.clone()).or_default() += 1;
                s.first_odom.get_or_insert(odom);
            }
            other => panic!("unexpected {other:?}"),
        }
    }
    s.stats = r.stats().clone();
    s.params = r.params().clone();
    Some(s)
}

fn counts(pairs: &[(&str, u64)]) -> BTreeMap<String, u64> {
    pairs.iter().map(|&(k, v)| (k.to_string(), v)).collect()
}

#[test]
fn intel_corrected() {
    let Some(s) = summarise("intel/intel-corrected.log.gz") else {
        return;
    };
    assert_eq!(s.by_topic, counts(&[("FLASER", 910), ("ODOM", 14541)]));
    assert_eq!(s.stats.skipped_by_type, counts(&[("NEFF", 910)]));
    assert_eq!(s.stats.malformed, 0);
    assert_eq!(s.beams, [(180, 910)].into());
    assert!(s.pose_is_odom);
    assert_eq!(s.params.get("robot_frontlaser_offset").unwrap(), "0.0");
    let first = s.first_scan.unwrap();
    assert_eq!(first.scan.stamp, Stamp(32_906_800_000));
    assert_eq!(first.pose, Some(Pose2::new(0.600266, -0.0320327, -0.354665)));
    assert_eq!(first.range_max, 81.0);
    assert_eq!(s.first_odom.unwrap().stamp, Stamp(246_000));
}

#[test]
fn freiburg_079_corrected() {
    let Some(s) = summarise("freiburg-079/freiburg-079-corrected.log.gz") else {
        return;
    };
    assert_eq!(s.by_topic, counts(&[("FLASER", 4791), ("ODOM", 9725)]));
    assert_eq!(s.stats.skipped_by_type, counts(&[("NEFF", 4791)]));
    assert_eq!(s.stats.malformed, 0);
    assert_eq!(s.beams, [(360, 4791)].into());
    assert_eq!(s.params.get("robot_front_laser_max").unwrap(), "80.99");
    let first = s.first_scan.unwrap();
    assert_eq!(first.scan.stamp, Stamp(227_623_000));
    assert_eq!(first.scan.angle_increment, PI / 360.0);
}

/// The other corrected logs: (file, FLASER, ODOM, NEFF, beams).
#[test]
fn other_corrected_logs() {
    let table = [
        ("csail/csail-corrected.log.gz", 406, 2394, 361),
        ("aces/aces-corrected.log.gz", 440, 7814, 180),
        ("freiburg-campus/freiburg-campus-corrected.log.gz", 2008, 17691, 360),
        ("infinite-corridor/infinite-corridor-corrected.log.gz", 1941, 18191, 180),
        ("seattle/seattle-corrected.log.gz", 241, 19311, 361),
        ("freiburg-101/freiburg-101-corrected.log.gz", 292, 4569, 360),
        ("orebro/orebro-corrected.log.gz", 237, 255, 181),
        ("fhw/fhw-corrected.log.gz", 488, 13935, 180),
        ("acapulco/acapulco-corrected.log.gz", 861, 12142, 181),
    ];
    for (file, flaser, odom, beams) in table {
        let Some(s) = summarise(file) else {
            continue;
        };
        assert_eq!(s.by_topic, counts(&[("FLASER", flaser), ("ODOM", odom)]), "{file}");
        assert_eq!(s.stats.skipped_by_type, counts(&[("NEFF", flaser)]), "{file}");
        assert_eq!(s.stats.malformed, 0, "{file}: {:?}", s.stats);
        assert_eq!(s.beams, [(beams, flaser)].into(), "{file}");
        assert!(s.pose_is_odom, "{file}");
    }
}

#[test]
fn csail_corrected_g_printed_stamps() {
    let Some(s) = summarise("csail/csail-corrected.log.gz") else {
        return;
    };
    // `%g` stamps are passed on as written, exactly.
    let first = s.first_scan.unwrap();
    assert_eq!(first.scan.stamp, Stamp(1_134_860_000_000_000_000));
    assert_eq!(first.receive_stamp, Some(first.scan.stamp));
}

#[test]
fn mit_csail_raw() {
    let Some(s) = summarise("mit-csail-raw/mit-csail.clf") else {
        return;
    };
    assert_eq!(s.by_topic, counts(&[("FLASER", 1988)]));
    assert!(s.stats.skipped_by_type.is_empty());
    assert_eq!(s.stats.malformed, 0);
    assert_eq!(s.beams, [(361, 1988)].into());
    assert!(s.pose_is_odom);
    let first = s.first_scan.unwrap();
    assert_eq!(first.scan.stamp, Stamp(1_134_864_629_895_182_000));
    assert_eq!(first.receive_stamp, Some(Stamp(86_295_000)));
    assert_eq!(first.pose, Some(Pose2::new(576.536523, 0.106594, -2.255213)));
    assert!((last_angle(&first) - PI / 2.0).abs() < 1e-12);
    assert_eq!(first.range_max, 81.0);
}

#[test]
#[allow(clippy::approx_constant)] // -1.570796 is the rounded start angle the log writes
fn csail_robotlaser_course() {
    let Some(s) = summarise("csail-robotlaser-course/csail.log") else {
        return;
    };
    assert_eq!(s.by_topic, counts(&[("ROBOTLASER1", 686)]));
    assert!(s.stats.skipped_by_type.is_empty());
    assert_eq!(s.stats.malformed, 0);
    assert_eq!(s.beams, [(361, 686)].into());
    let first = s.first_scan.unwrap();
    assert_eq!(first.scan.angle_min, -1.570796);
    assert_eq!(first.scan.angle_increment, 0.008727);
    assert_eq!(first.range_max, 80.0);
    assert_eq!(first.scan.stamp, Stamp(1_134_864_642_914_187_000));
    assert_eq!(first.receive_stamp, Some(Stamp(430_003_000)));
    assert_eq!(first.pose, Some(Pose2::IDENTITY));
    assert_eq!(first.laser_pose, Some(Pose2::IDENTITY));
    assert_eq!(first.odom_pose, None);
}

/// What `open`-by-content passes: the first 4 KiB of the file, gzipped or not.
#[test]
fn sniff_on_shared_files() {
    let carmen = [
        "intel/intel-corrected.log.gz",
        "freiburg-079/freiburg-079-corrected.log.gz",
        "freiburg-campus/freiburg-campus-corrected.log.gz",
        "infinite-corridor/infinite-corridor-corrected.log.gz",
        "orebro/orebro-corrected.log.gz",
        "mit-csail-raw/mit-csail.clf",
        "csail-robotlaser-course/csail.log",
    ];
    let other = ["rosbag1-slam-benchmark/intel.orig.bag", "slam-benchmark-relations/intel.relations"];
    for (files, expected) in [(&carmen[..], true), (&other[..], false)] {
        for file in files {
            let Some(path) = crate::testdata::dataset(file) else {
                continue;
            };
            let mut head = Vec::new();
            File::open(path).unwrap().take(4096).read_to_end(&mut head).unwrap();
            assert_eq!(sniff(&head), expected, "{file}");
        }
    }
}

#[test]
fn truncated_gzip_file_is_a_format_error() {
    let Some(src) = crate::testdata::dataset("intel/intel-corrected.log.gz") else {
        return;
    };
    let bytes = std::fs::read(src).unwrap();
    let dir = crate::testdata::temp_dir("carmen-truncated");
    let cut = dir.join("intel-truncated.log.gz");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let mut r = CarmenReader::open(&cut, CarmenOptions::default()).unwrap();
    let mut ok = 0;
    let mut error = None;
    for m in r.by_ref() {
        match m {
            Ok(_) => ok += 1,
            Err(e) => error = Some(e),
        }
    }
    drop(dir);
    let error = error.expect("a truncated stream must be an error").to_string();
    let lines = r.line_number();
    assert!(ok > 1000 && lines > 1000, "{ok} messages, {lines} lines");
    assert_eq!(error, format!("{}: gzip stream ends early after line {lines}", cut.display()));
}

#[test]
fn a_line_past_the_limit_ends_the_read_naming_it() {
    let line = flaser_n(181);
    let n = line.len() as u64 - 1; // without its newline
    let text = format!("{line}{line}{}\n{line}", "9".repeat(5000));
    // Gzipped, as the bombs come: the reader must stop at the limit, not inflate the line.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(text.as_bytes()).unwrap();
    let gz = gz.finish().unwrap();
    for bytes in [text.as_bytes(), &gz[..]] {
        let read = |limit: u64| {
            let options = CarmenOptions { max_line_bytes: Some(limit), ..Default::default() };
            CarmenReader::from_reader("big.log", bytes, options).unwrap().collect::<Vec<_>>()
        };
        // Lines up to the limit (newline not counted) read; the 5000-byte one is refused.
        let got = read(4999);
        assert_eq!(got.len(), 3);
        assert!(got[0].is_ok() && got[1].is_ok());
        match &got[2] {
            Err(Error::Limit { path, location: Location::Line(3), message }) => {
                assert_eq!(path, Path::new("big.log"));
                assert!(
                    message.contains("limit of 4999 bytes") && message.contains("limits.decompressed_mib"),
                    "{message}"
                );
            }
            other => panic!("{other:?}"),
        }
        // At exactly the line's length it is read (and skipped as malformed: not a record).
        let got = read(5000);
        assert!(got.iter().all(|m| m.is_ok()) && got.len() == 3, "{got:?}");
        assert!(read(n).len() == 3 && read(n - 1).len() == 1);
    }
}

#[test]
fn a_scan_past_the_beam_limit_ends_the_read_naming_the_key() {
    let text = format!("{}{}", flaser_n(181), flaser_n(361));
    let read = |max_beams| {
        let options = CarmenOptions { max_beams, ..Default::default() };
        CarmenReader::from_reader("wide.log", text.as_bytes(), options).unwrap().collect::<Vec<_>>()
    };
    assert!(read(None).iter().all(|m| m.is_ok()));
    assert!(read(Some(361)).iter().all(|m| m.is_ok()));
    let got = read(Some(360));
    assert!(got[0].is_ok());
    match &got[1] {
        Err(Error::Limit { location: Location::Line(2), message, .. }) => {
            assert!(message.contains("361 beams, over the limit of 360 (limits.beams_per_scan"), "{message}")
        }
        other => panic!("{other:?}"),
    }
}
