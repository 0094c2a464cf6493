use super::*;
use crate::log::ros2::cdr::CdrReader;
use crate::log::ros2::msgs::wire::FieldReader;
use crate::semantic::ClassInfo;
use fusemap_core::grid::CellIndex;

fn raster() -> Raster {
    crate::testdata::raster_3x2([0.2, 0.9, 0.5, 0.3, 0.6504, 0.95], [true, true, true, true, true, false])
}

/// Every message of `path`, as (topic, schema name, payload).
fn read(path: &Path) -> Vec<(String, String, Vec<u8>)> {
    let bytes = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            assert_eq!(schema.encoding, "ros2msg");
            assert_eq!(m.channel.message_encoding, "cdr");
            (m.channel.topic.clone(), schema.name.clone(), m.data.to_vec())
        })
        .collect()
}

#[test]
fn the_map_the_track_and_the_points_as_ros_messages() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("map.mcap");
    let r = raster();
    let cloud = MapCloud::occupied_cells(&r, None);
    let track = [(Stamp(1_000_000_000), Pose2::new(1.0, 2.0, 0.5)), (Stamp(2_000_000_000), Pose2::new(2.0, 2.0, 0.0))];
    let closures = [(Point2::new(0.0, 0.0), Point2::new(1.0, 1.0))];
    let content = MapMessages {
        raster: &r,
        stamp: Stamp(2_000_000_000),
        trajectory: &track,
        cloud: &cloud,
        semantic: None,
        dynamic: None,
        closures: &closures,
        map_from_odom: Some(("odom", Pose2::new(0.5, -1.0, std::f64::consts::FRAC_PI_2))),
    };
    write_map_mcap(&path, &content).unwrap();
    let messages = read(&path);
    let topics: Vec<(&str, &str)> = messages.iter().map(|(t, s, _)| (t.as_str(), s.as_str())).collect();
    assert_eq!(
        topics,
        [
            ("/map", "nav_msgs/msg/OccupancyGrid"),
            ("/trajectory", "nav_msgs/msg/Path"),
            ("/map_points", "sensor_msgs/msg/PointCloud2"),
            ("/slam/loop_closures", "visualization_msgs/msg/MarkerArray"),
            ("/tf_static", "tf2_msgs/msg/TFMessage"),
        ]
    );
    // /tf_static: one transform, map → odom, the odometry frame's pose in the map.
    let mut c = CdrReader::new(&messages[4].2[4..]);
    assert_eq!(c.u32("transforms").unwrap(), 1);
    assert_eq!((c.i32("sec").unwrap(), c.u32("ns").unwrap()), (2, 0));
    assert_eq!((c.string("frame").unwrap(), c.string("child").unwrap()), ("map".into(), "odom".into()));
    let t: Vec<f64> = (0..7).map(|_| c.f64("transform").unwrap()).collect();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert_eq!(t[..3], [0.5, -1.0, 0.0]);
    assert!(t[3..5] == [0.0, 0.0] && (t[5] - h).abs() < 1e-15 && (t[6] - h).abs() < 1e-15, "{t:?}");
    assert_eq!(c.remaining(), 0);
    // /map: header (stamp 2 s, "map"), map_load_time, resolution, width, height, origin, data.
    let mut c = CdrReader::new(&messages[0].2[4..]);
    assert_eq!((c.i32("sec").unwrap(), c.u32("ns").unwrap()), (2, 0));
    assert_eq!(c.string("frame").unwrap(), "map");
    assert_eq!((c.i32("sec").unwrap(), c.u32("ns").unwrap()), (2, 0));
    assert_eq!(c.f32("resolution").unwrap(), 0.5);
    assert_eq!((c.u32("w").unwrap(), c.u32("h").unwrap()), (3, 2));
    let origin: Vec<f64> = (0..7).map(|_| c.f64("origin").unwrap()).collect();
    assert_eq!(origin, [10.0, 20.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    assert_eq!(c.u32("len").unwrap(), 6);
    let data: Vec<i8> = (0..6).map(|_| c.u8("d").unwrap() as i8).collect();
    assert_eq!(data, [20, 90, 50, 30, 66, -1]);
    assert_eq!(c.remaining(), 0);
}

#[test]
fn a_camera_run_adds_its_layers_and_palette() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("map.mcap");
    let r = raster();
    let semantic = SemanticRaster {
        width: 3,
        height: 2,
        resolution: 0.5,
        origin: [10.0, 20.0],
        classes: vec![ClassInfo { id: 3, name: "wall".into(), color: [9, 9, 9] }],
        best: vec![0, -1, -1, -1, -1, 0],
        prob: vec![0.0; 6],
        probs: Vec::new(),
    };
    let dynamic = CellRaster {
        width: 3,
        height: 2,
        resolution: 0.5,
        origin: Point2::new(10.0, 20.0),
        first_cell: CellIndex::new(0, 0),
        cells: vec![0.25, 0.0, f32::NAN, 1.0, 0.5, 0.5],
        known: vec![true, true, true, true, true, false],
    };
    let cloud = MapCloud::occupied_cells(&r, Some((&semantic.best, &semantic.classes)));
    let content = MapMessages {
        raster: &r,
        stamp: Stamp(-5),
        trajectory: &[],
        cloud: &cloud,
        semantic: Some(&semantic),
        dynamic: Some(&dynamic),
        closures: &[],
        map_from_odom: None,
    };
    write_map_mcap(&path, &content).unwrap();
    let messages = read(&path);
    let topics: Vec<&str> = messages.iter().map(|(t, _, _)| t.as_str()).collect();
    assert_eq!(topics, ["/map", "/trajectory", "/map_points", "/map/semantic", "/map/dynamic"]);
    // The image's last 3 bytes are its top row (row 0 of the image = highest y).
    let image = &messages[3].2;
    assert_eq!(&image[image.len() - 6..], &[1, 1, 0, 0, 1, 1], "bottom row [0, K, K] last, top row [K, K, 0] first");
    let dynamic = &messages[4].2;
    assert_eq!(&dynamic[dynamic.len() - 6..], &[25, 0, 0xff, 100, 50, 0xff]);
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    assert_eq!(summary.metadata_indexes.len(), 1);
    assert_eq!(summary.metadata_indexes[0].name, "semantic");
}
