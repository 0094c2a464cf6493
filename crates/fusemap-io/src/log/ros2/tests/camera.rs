//! CDR payloads of `sensor_msgs/msg/Image` and `sensor_msgs/msg/CameraInfo` laid out by
//! hand, and images in MCAP and `.db3` files read with and without their pixels.

use super::*;

/// One image as a test writes it.
pub(super) struct Img<'a> {
    pub sec: i32,
    pub frame: &'a str,
    pub width: u32,
    pub height: u32,
    pub encoding: &'a str,
    pub big_endian: u8,
    pub step: u32,
    pub data: Vec<u8>,
}

impl Img<'_> {
    /// A 3 × 2 `mono8` image with rows padded to 4 bytes.
    pub fn labels() -> Self {
        Img {
            sec: 7,
            frame: "cam_optical",
            width: 3,
            height: 2,
            encoding: "mono8",
            big_endian: 0,
            step: 4,
            data: vec![1, 2, 3, 0xEE, 4, 5, 6, 0xEE],
        }
    }

    /// CDR: header; `uint32 height`, `uint32 width`; `string encoding`; `uint8
    /// is_bigendian`; `uint32 step` (aligned to 4); `sequence<uint8> data`.
    pub fn payload(&self) -> Vec<u8> {
        let mut w = W::new();
        w.header(self.sec, 500, self.frame).u32(self.height).u32(self.width).string(self.encoding);
        w.buf.push(self.big_endian);
        w.u32(self.step).u32(self.data.len() as u32);
        w.buf.extend_from_slice(&self.data);
        w.done()
    }
}

/// CDR `sensor_msgs/msg/CameraInfo` with `d` and a recognisable `k`; r, p, binning and
/// roi filled with values a misaligned read would take for `k`.
pub(super) fn camera_info_payload(d: &[f64], k: [f64; 9]) -> Vec<u8> {
    let mut w = W::new();
    w.header(7, 250, "cam_optical").u32(480).u32(640).string("plumb_bob").u32(d.len() as u32).f64s(d).f64s(&k);
    w.f64s(&[9.0; 9]).f64s(&[8.0; 12]).u32(1).u32(1).u32(0).u32(0).u32(0).u32(0);
    w.buf.push(1);
    w.done()
}

pub(super) fn sample_k() -> [f64; 9] {
    [525.0, 0.0, 319.5, 0.0, 526.0, 239.5, 0.0, 0.0, 1.0]
}

#[test]
fn an_image_decodes_with_or_without_its_pixels() {
    let img = Img::labels();
    let p = img.payload();
    let LogMessage::Image(m) = decode_known(KnownType::Image, "/labels", Some(Stamp(3)), &p).unwrap() else {
        panic!("an image with pixels")
    };
    assert_eq!((m.width, m.height, m.step, m.encoding.as_str(), m.is_bigendian), (3, 2, 4, "mono8", false));
    assert_eq!((m.stamp, m.receive_stamp, m.frame_id.as_str()), (Stamp(7_000_000_500), Some(Stamp(3)), "cam_optical"));
    assert_eq!(m.data, img.data);
    let LogMessage::ImageHeader(h) = decode_known_with(KnownType::Image, "/labels", Some(Stamp(3)), &p, false).unwrap()
    else {
        panic!("an image header")
    };
    assert_eq!(h, m.header());
    assert_eq!(h.data_len, 8);
    let labels = crate::camera::labels(&m).unwrap();
    assert_eq!(labels.labels, [1, 2, 3, 4, 5, 6]);
}

#[test]
fn image_layouts_that_do_not_fit_are_errors_at_the_data() {
    let cases = [
        (Img { step: 5, ..Img::labels() }, "= 10 bytes, but the data holds 8"),
        (Img { step: 2, ..Img::labels() }, "step 2 is shorter than a row of 3 mono8 pixels"),
        // Found by fuzzing the camera decoding: a billion rows of nothing.
        (Img { width: 0, height: 1_124_073_476, step: 0, ..Img::labels() }, "rows but no columns"),
        (Img { encoding: "16UC1", ..Img::labels() }, "shorter than a row of 3 16UC1 pixels"),
    ];
    for (img, needle) in cases {
        for pixels in [true, false] {
            let e = decode_known_with(KnownType::Image, "/labels", None, &img.payload(), pixels).unwrap_err();
            assert!(matches!(&e, CdrError::Invalid { field, .. } if field == "data"), "{e}");
            assert!(e.to_string().contains(needle), "{e}");
        }
    }
    // A data length beyond the payload is a truncation, checked before any allocation.
    let mut p = Img::labels().payload();
    let n = p.len();
    p[n - 12..n - 8].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = decode_known(KnownType::Image, "/labels", None, &p).unwrap_err();
    assert!(matches!(&e, CdrError::Truncated { field, .. } if field == "data"), "{e}");
}

#[test]
fn camera_info_keeps_d_and_k() {
    let d = [0.1, -0.2, 0.001, 0.002, 0.05];
    let p = camera_info_payload(&d, sample_k());
    let LogMessage::CameraInfo(c) = decode_known(KnownType::CameraInfo, "/camera_info", None, &p).unwrap() else {
        panic!("camera info")
    };
    assert_eq!((c.width, c.height, c.distortion_model.as_str()), (640, 480, "plumb_bob"));
    assert_eq!((c.d.as_slice(), c.k), (&d[..], sample_k()));
    assert_eq!((c.stamp, c.frame_id.as_str()), (Stamp(7_000_000_250), "cam_optical"));
    // No distortion coefficients: k right after the count, aligned to 8.
    let p = camera_info_payload(&[], sample_k());
    let LogMessage::CameraInfo(c) = decode_known(KnownType::CameraInfo, "/ci", None, &p).unwrap() else { panic!() };
    assert!(c.d.is_empty());
    assert_eq!(c.k, sample_k());
}

fn camera_log() -> Vec<Msg<'static>> {
    vec![
        ("/camera_info", "sensor_msgs/msg/CameraInfo", "cdr", 1_000, camera_info_payload(&[0.0; 5], sample_k())),
        ("/labels", "sensor_msgs/msg/Image", "cdr", 2_000, Img::labels().payload()),
        ("/scan", "sensor_msgs/msg/LaserScan", "cdr", 2_500, scan_payload(2, 0, "laser", &[3.0])),
        ("/labels", "sensor_msgs/msg/Image", "cdr", 3_000, Img { step: 9, ..Img::labels() }.payload()),
        ("/depth", "sensor_msgs/msg/Image", "cdr", 4_000, {
            let metres: Vec<u8> = [1.0f32, 2.0, 4.0].iter().flat_map(|v| v.to_le_bytes()).collect();
            Img { encoding: "32FC1", width: 3, height: 1, step: 12, data: metres, ..Img::labels() }.payload()
        }),
    ]
}

/// What a reader gave: per message a short description, errors as `error`.
fn kinds(reader: &mut dyn LogReader) -> Vec<String> {
    read_all(reader)
        .into_iter()
        .map(|m| match m {
            Ok(LogMessage::Image(i)) => format!("image {} {}", i.topic, i.data.len()),
            Ok(LogMessage::ImageHeader(h)) => format!("header {} {}", h.topic, h.data_len),
            Ok(LogMessage::CameraInfo(c)) => format!("info {}", c.k[0]),
            Ok(m) => m.topic().to_string(),
            Err(e) => {
                assert!(e.is_skippable(), "{e}");
                assert!(e.to_string().contains("truncated"), "{e}");
                "error".into()
            }
        })
        .collect()
}

#[test]
fn mcap_and_db3_give_pixels_only_for_the_topics_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let mcap = dir.path().join("cam.mcap");
    let db3 = dir.path().join("cam.db3");
    write_mcap(&mcap, Some(mcap::Compression::Zstd), &camera_log());
    write_db3(&db3, &camera_log(), false);
    for path in [&mcap, &db3] {
        let mut r = Ros2Reader::open(path).unwrap();
        assert_eq!(
            kinds(&mut r),
            ["info 525", "header /labels 8", "/scan", "error", "header /depth 12"],
            "{}",
            path.display()
        );
        let mut r = Ros2Reader::open_with(path, ReadOptions::with_image_topics(["/depth"])).unwrap();
        assert_eq!(kinds(&mut r), ["info 525", "header /labels 8", "/scan", "error", "image /depth 12"]);
        let mut r =
            Ros2Reader::open_with(path, ReadOptions { images: crate::log::ImagePayloads::All, ..Default::default() })
                .unwrap();
        assert_eq!(kinds(&mut r), ["info 525", "image /labels 8", "/scan", "error", "image /depth 12"]);
        assert!(r.stats().skipped_by_type.is_empty());
    }
    // open_log_with reaches the same reader.
    let opened = crate::log::open_log_with(&mcap, &ReadOptions::with_image_topics(["/labels"])).unwrap();
    let mut reader = opened.reader;
    assert_eq!(kinds(reader.as_mut())[1], "image /labels 8");
}
