use super::*;
use fusemap_core::time::Stamp;
use proptest::prelude::*;

/// An image message of `encoding` with rows of `step` bytes built from `pixels` (each
/// pixel's bytes), padded with 0xEE so a decoder reading padding shows it.
fn image(encoding: &str, width: u32, height: u32, step: u32, big_endian: bool, pixels: &[Vec<u8>]) -> ImageMessage {
    let mut data = Vec::new();
    for row in pixels.chunks(width.max(1) as usize) {
        let start = data.len();
        for p in row {
            data.extend_from_slice(p);
        }
        data.resize(start + step as usize, 0xEE);
    }
    ImageMessage {
        topic: "/camera/labels".into(),
        stamp: Stamp(1),
        receive_stamp: None,
        frame_id: "camera_optical".into(),
        width,
        height,
        encoding: encoding.into(),
        is_bigendian: big_endian,
        step,
        data,
    }
}

#[test]
fn eight_bit_labels_with_padded_rows() {
    for encoding in ["mono8", "8UC1"] {
        let px: Vec<Vec<u8>> = (0..6u8).map(|v| vec![v * 10]).collect();
        let m = image(encoding, 3, 2, 5, false, &px);
        let l = labels(&m).unwrap();
        assert_eq!((l.width, l.height), (3, 2));
        assert_eq!(l.labels, [0, 10, 20, 30, 40, 50], "{encoding}");
        assert_eq!(l.at(2, 1), 50);
    }
}

#[test]
fn sixteen_bit_labels_in_both_byte_orders() {
    let ids: [u16; 4] = [1, 300, 0xABCD, 7];
    for encoding in ["mono16", "16UC1"] {
        let le: Vec<Vec<u8>> = ids.iter().map(|v| v.to_le_bytes().to_vec()).collect();
        let be: Vec<Vec<u8>> = ids.iter().map(|v| v.to_be_bytes().to_vec()).collect();
        assert_eq!(labels(&image(encoding, 2, 2, 4, false, &le)).unwrap().labels, ids);
        assert_eq!(labels(&image(encoding, 2, 2, 6, true, &be)).unwrap().labels, ids);
        // The same bytes read with the other byte order give other ids: the flag is used.
        assert_ne!(labels(&image(encoding, 2, 2, 4, true, &le)).unwrap().labels, ids);
    }
}

#[test]
fn float_depth_in_metres_passes_invalid_values_on() {
    let d = [1.5f32, f32::NAN, 0.0, -2.0, f32::INFINITY, 12.25];
    let le: Vec<Vec<u8>> = d.iter().map(|v| v.to_le_bytes().to_vec()).collect();
    let be: Vec<Vec<u8>> = d.iter().map(|v| v.to_be_bytes().to_vec()).collect();
    for m in [image("32FC1", 3, 2, 12, false, &le), image("32FC1", 3, 2, 16, true, &be)] {
        let out = depth(&m).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&out.metres), bits(&d));
    }
}

#[test]
fn millimetre_depth_becomes_metres_and_zero_becomes_nan() {
    let mm: [u16; 4] = [1000, 0, 1, 65535];
    for encoding in ["16UC1", "mono16"] {
        for big in [false, true] {
            let px: Vec<Vec<u8>> =
                mm.iter().map(|v| if big { v.to_be_bytes() } else { v.to_le_bytes() }.to_vec()).collect();
            let out = depth(&image(encoding, 4, 1, 8, big, &px)).unwrap();
            assert_eq!(out.metres[0], 1.0);
            assert!(out.metres[1].is_nan(), "0 mm is no depth");
            assert_eq!(out.metres[2], 0.001);
            assert_eq!(out.metres[3], 65.535);
        }
    }
}

#[test]
fn unsupported_encodings_are_named_with_the_supported_ones() {
    for encoding in ["rgb8", "bgr8", "32FC3", "bayer_rggb8", ""] {
        let m = ImageMessage { encoding: encoding.into(), ..image("mono8", 1, 1, 1, false, &[vec![0]]) };
        let e = labels(&m).unwrap_err().to_string();
        assert!(e.contains(&format!("`{encoding}`")) && e.contains("mono8, 8UC1, mono16, 16UC1"), "{e}");
        let e = depth(&m).unwrap_err().to_string();
        assert!(e.contains(&format!("`{encoding}`")) && e.contains("32FC1, 16UC1, mono16"), "{e}");
        assert!(e.contains("/camera/labels"), "{e}");
    }
    // Labels are not depth: mono8 is refused as depth, 32FC1 as labels.
    assert!(depth(&image("mono8", 1, 1, 1, false, &[vec![3]])).is_err());
    assert!(labels(&image("32FC1", 1, 1, 4, false, &[1f32.to_le_bytes().to_vec()])).is_err());
}

#[test]
fn bad_layouts_are_errors_not_panics() {
    let px: Vec<Vec<u8>> = (0..4u8).map(|v| vec![v]).collect();
    // Truncated data.
    let mut m = image("mono8", 2, 2, 2, false, &px);
    m.data.pop();
    let e = labels(&m).unwrap_err();
    assert!(matches!(&e, CameraDecodeError::Layout { reason, .. } if reason.contains("truncated")), "{e}");
    // A step shorter than a row.
    let m = ImageMessage { step: 3, ..image("16UC1", 2, 2, 4, false, &vec![vec![0, 0]; 4]) };
    let e = depth(&m).unwrap_err().to_string();
    assert!(e.contains("step 3") && e.contains("4 bytes"), "{e}");
    // A huge declared width with almost no data: refused before any allocation.
    let m = ImageMessage { width: u32::MAX, height: u32::MAX, step: u32::MAX, ..image("mono8", 1, 1, 1, false, &px) };
    let e = labels(&m).unwrap_err().to_string();
    assert!(e.contains("truncated"), "{e}");
    let m = ImageMessage { width: 1 << 20, height: 1, step: 1 << 22, ..image("32FC1", 1, 1, 4, false, &[vec![0; 4]]) };
    assert!(depth(&m).unwrap_err().to_string().contains("truncated"));
}

#[test]
fn label_and_depth_sizes_are_reported_and_compared() {
    let l = labels(&image("mono8", 3, 2, 3, false, &vec![vec![1]; 6])).unwrap();
    let d = depth(&image("32FC1", 2, 2, 8, false, &vec![1f32.to_le_bytes().to_vec(); 4])).unwrap();
    assert_eq!((l.width, l.height, d.width, d.height), (3, 2, 2, 2));
    let e = check_same_size(&l, &d).unwrap_err();
    assert_eq!(e.to_string(), "labels are 3×2 but depth is 2×2: they must be aligned pixel for pixel");
    let d2 = depth(&image("16UC1", 3, 2, 6, false, &vec![vec![1, 0]; 6])).unwrap();
    assert!(check_same_size(&l, &d2).is_ok());
}

proptest! {
    /// Any bytes in any layout: a decode either succeeds with width × height pixels or
    /// fails with an error, never panics.
    #[test]
    fn any_layout_decodes_or_fails_cleanly(
        width in 0u32..40,
        height in 0u32..40,
        step in 0u32..200,
        big in any::<bool>(),
        encoding in prop::sample::select(vec!["mono8", "8UC1", "mono16", "16UC1", "32FC1", "rgb8"]),
        data in prop::collection::vec(any::<u8>(), 0..2000),
    ) {
        let m = ImageMessage { width, height, step, is_bigendian: big, encoding: encoding.into(), data,
            ..image("mono8", 0, 0, 0, false, &[]) };
        if let Ok(l) = labels(&m) {
            prop_assert_eq!(l.labels.len() as u64, u64::from(width) * u64::from(height));
        }
        if let Ok(d) = depth(&m) {
            prop_assert_eq!(d.metres.len() as u64, u64::from(width) * u64::from(height));
        }
    }
}
