//! ROS 1 payloads of `sensor_msgs/Image` and `sensor_msgs/CameraInfo` laid out byte by
//! byte, read through whole bags with and without the pixels.

use super::*;
use crate::log::{ImagePayloads, ReadOptions};

const IMAGE_MD5: &str = "060021388200f6f0f447d0fcd9c64743";
const INFO_MD5: &str = "c9a58c1b0b154e0e6da7578cb991d214";
const LABELS: Conn = Conn { id: 8, topic: "/labels", ty: "sensor_msgs/Image", md5: IMAGE_MD5 };
const DEPTH: Conn = Conn { id: 9, topic: "/depth", ty: "sensor_msgs/Image", md5: IMAGE_MD5 };
const INFO: Conn = Conn { id: 10, topic: "/camera_info", ty: "sensor_msgs/CameraInfo", md5: INFO_MD5 };

/// ROS 1 `sensor_msgs/Image`: header; height, width; encoding; `uint8 is_bigendian`;
/// step; `uint8[] data` (no padding anywhere).
fn image_payload(width: u32, height: u32, encoding: &str, big_endian: u8, step: u32, data: &[u8]) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 3, (20, 5), "cam_optical");
    p.extend(height.to_le_bytes());
    p.extend(width.to_le_bytes());
    ros_string(&mut p, encoding);
    p.push(big_endian);
    p.extend(step.to_le_bytes());
    p.extend((data.len() as u32).to_le_bytes());
    p.extend(data);
    p
}

/// ROS 1 `sensor_msgs/CameraInfo`: header; height, width; distortion_model; `float64[] D`;
/// K, R, P; binning; roi.
fn info_payload(d: &[f64], k: [f64; 9]) -> Vec<u8> {
    let mut p = Vec::new();
    ros_header(&mut p, 4, (20, 5), "cam_optical");
    p.extend(480u32.to_le_bytes());
    p.extend(640u32.to_le_bytes());
    ros_string(&mut p, "plumb_bob");
    p.extend((d.len() as u32).to_le_bytes());
    f64s(&mut p, d);
    f64s(&mut p, &k);
    f64s(&mut p, &[7.0; 9]);
    f64s(&mut p, &[6.0; 12]);
    for v in [1u32, 1, 0, 0, 0, 0] {
        p.extend(v.to_le_bytes());
    }
    p.push(0);
    p
}

const K: [f64; 9] = [525.0, 0.0, 319.5, 0.0, 526.0, 239.5, 0.0, 0.0, 1.0];

/// A bag with a camera info, a 2 × 2 big-endian mono16 label image with padded rows, a
/// 2 × 1 16UC1 depth image, and a scan.
fn camera_bag(compression: Compression) -> Vec<u8> {
    let labels: Vec<u8> = [0x01, 0x02, 0x03, 0x04, 0xEE, 0x05, 0x06, 0x07, 0x08, 0xEE].to_vec();
    let depth: Vec<u8> = [1500u16, 0].iter().flat_map(|v| v.to_le_bytes()).collect();
    bag(vec![(
        compression,
        vec![
            Inner::Conn(INFO),
            Inner::Conn(LABELS),
            Inner::Conn(DEPTH),
            Inner::Conn(SCAN),
            msg(INFO, (20, 6), info_payload(&[0.1, -0.2, 0.0, 0.0, 0.01], K)),
            msg(LABELS, (20, 7), image_payload(2, 2, "mono16", 1, 5, &labels)),
            msg(DEPTH, (20, 8), image_payload(2, 1, "16UC1", 0, 4, &depth)),
            msg(SCAN, (20, 9), scan_payload((20, 0), &[1.0], &[])),
        ],
    )])
}

fn read_with(bytes: &[u8], options: ReadOptions) -> Vec<LogMessage> {
    let mut reader = BagReader::from_reader(bytes, "test.bag").unwrap();
    reader.set_options(options);
    let out = std::iter::from_fn(|| reader.next_message()).map(|m| m.unwrap()).collect();
    assert!(reader.stats().skipped_by_type.is_empty());
    out
}

#[test]
fn images_and_camera_info_decode_in_every_compression() {
    for compression in [Compression::None, Compression::Bz2, Compression::Lz4] {
        let bytes = camera_bag(compression);
        let all = read_with(&bytes, ReadOptions { images: ImagePayloads::All, ..Default::default() });
        assert_eq!(all.len(), 4);
        let LogMessage::CameraInfo(c) = &all[0] else { panic!("{:?}", all[0]) };
        assert_eq!((c.width, c.height, c.distortion_model.as_str()), (640, 480, "plumb_bob"));
        assert_eq!((c.d.clone(), c.k), (vec![0.1, -0.2, 0.0, 0.0, 0.01], K));
        assert_eq!((c.stamp, c.receive_stamp), (Stamp(20_000_000_005), Some(Stamp(20_000_000_006))));
        let LogMessage::Image(l) = &all[1] else { panic!("{:?}", all[1]) };
        assert_eq!((l.width, l.height, l.step, l.encoding.as_str(), l.is_bigendian), (2, 2, 5, "mono16", true));
        assert_eq!(l.frame_id, "cam_optical");
        assert_eq!(crate::camera::labels(l).unwrap().labels, [0x0102, 0x0304, 0x0506, 0x0708]);
        let LogMessage::Image(d) = &all[2] else { panic!("{:?}", all[2]) };
        let metres = crate::camera::depth(d).unwrap().metres;
        assert_eq!(metres[0], 1.5);
        assert!(metres[1].is_nan());
        assert!(matches!(all[3], LogMessage::Scan(_)));
    }
}

#[test]
fn by_default_images_are_headers_and_only_the_asked_topics_get_pixels() {
    let bytes = camera_bag(Compression::Lz4);
    let headers = read_with(&bytes, ReadOptions::default());
    let LogMessage::ImageHeader(h) = &headers[1] else { panic!("{:?}", headers[1]) };
    assert_eq!((h.topic.as_str(), h.width, h.height, h.data_len), ("/labels", 2, 2, 10));
    assert_eq!((h.stamp, h.frame_id.as_str()), (Stamp(20_000_000_005), "cam_optical"));
    assert!(matches!(&headers[2], LogMessage::ImageHeader(h) if h.encoding == "16UC1"));
    let some = read_with(&bytes, ReadOptions::with_image_topics(["/depth"]));
    assert!(matches!(&some[1], LogMessage::ImageHeader(_)));
    assert!(matches!(&some[2], LogMessage::Image(i) if i.data.len() == 4));
    // The full image's header is what the header-only pass saw.
    let all = read_with(&bytes, ReadOptions { images: ImagePayloads::All, ..Default::default() });
    let LogMessage::Image(full) = &all[1] else { panic!() };
    assert_eq!(&full.header(), h);
}

#[test]
fn bad_images_are_skippable_message_errors_and_reading_goes_on() {
    let cases: [(Vec<u8>, &str); 5] = [
        (image_payload(3, 2, "mono8", 0, 3, &[0; 5]), "the data holds 5: the image is truncated"),
        (image_payload(3, 2, "mono16", 0, 4, &[0; 8]), "step 4 is shorter than a row of 3 mono16 pixels"),
        (image_payload(u32::MAX, 1 << 20, "mono8", 0, 0, &[]), "step 0 is shorter than a row"),
        (image_payload(0, 1_124_073_476, "16UC1", 0, 0, &[]), "rows but no columns"),
        (
            {
                let mut p = image_payload(1, 1, "mono8", 0, 1, &[7]);
                let n = p.len();
                p[n - 5..n - 1].copy_from_slice(&u32::MAX.to_le_bytes());
                p
            },
            "data: claims",
        ),
    ];
    for (payload, needle) in cases {
        for options in [ReadOptions::default(), ReadOptions { images: ImagePayloads::All, ..Default::default() }] {
            let bytes = bag(vec![(
                Compression::None,
                vec![
                    Inner::Conn(LABELS),
                    Inner::Conn(SCAN),
                    msg(LABELS, (1, 0), payload.clone()),
                    msg(SCAN, (2, 0), scan_payload((2, 0), &[1.0], &[])),
                ],
            )]);
            let mut reader = BagReader::from_reader(&bytes[..], "test.bag").unwrap();
            reader.set_options(options);
            let e = reader.next_message().unwrap().unwrap_err();
            assert!(e.is_skippable(), "{e}");
            let text = e.to_string();
            assert!(text.contains("Image") && text.contains(needle), "{text}");
            assert!(matches!(reader.next_message(), Some(Ok(LogMessage::Scan(_)))));
        }
    }
}

#[test]
fn images_and_scans_past_their_limits_end_the_read_naming_the_key() {
    let bytes = camera_bag(Compression::None);
    let limits = fusemap_core::config::LimitsConfig { image_pixels: 3, beams_per_scan: 1, ..Default::default() };
    // Header-only images take no pixel memory: the pixel budget does not apply to them.
    assert_eq!(read_with(&bytes, ReadOptions::within(&limits)).len(), 4);
    let mut reader = BagReader::from_reader(&bytes[..], "test.bag").unwrap();
    reader.set_options(ReadOptions::within(&limits).images_of(["/labels"]));
    assert!(matches!(reader.next_message(), Some(Ok(LogMessage::CameraInfo(_)))));
    let e = reader.next_message().unwrap().unwrap_err();
    assert!(matches!(e, crate::Error::Limit { .. }) && !e.is_skippable(), "{e}");
    let text = e.to_string();
    for part in ["test.bag", "/labels", "2 × 2 image is 4 pixels", "limit of 3", "limits.image_pixels"] {
        assert!(text.contains(part), "{part}: {text}");
    }
    let limits = fusemap_core::config::LimitsConfig { beams_per_scan: 1, ..Default::default() };
    let wide = bag(vec![(
        Compression::None,
        vec![Inner::Conn(SCAN), msg(SCAN, (2, 0), scan_payload((2, 0), &[1.0, 2.0], &[]))],
    )]);
    let mut reader = BagReader::from_reader(&wide[..], "test.bag").unwrap();
    reader.set_options(ReadOptions::within(&limits));
    let e = reader.next_message().unwrap().unwrap_err();
    assert!(matches!(e, crate::Error::Limit { .. }), "{e}");
    assert!(e.to_string().contains("a scan of 2 beams, over the limit of 1 (limits.beams_per_scan"), "{e}");
}

#[test]
fn trailing_bytes_after_an_image_or_info_are_refused() {
    let mut p = info_payload(&[], K);
    p.push(0);
    let bytes = bag(vec![(Compression::None, vec![Inner::Conn(INFO), msg(INFO, (1, 0), p)])]);
    let (_, e, _) = read_bytes(&bytes);
    let (_, m) = format_error(e);
    assert!(m.contains("CameraInfo: 1 bytes left over"), "{m}");
}
