use super::read::parse_header;
use super::*;
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{CellIndex, OccupancyParams};
use std::fs::File;
use zip::ZipArchive;

fn temp_dir(tag: &str) -> crate::testdata::TestDir {
    crate::testdata::temp_dir(&format!("npz-{tag}"))
}

/// A 3-row, 4-column raster whose log-odds encode their position, `(row * 10 + col) / 8
/// - 1`, unknown on the diagonal.
fn raster() -> Raster {
    let (width, height) = (4, 3);
    let mut log_odds = Vec::new();
    let mut known = Vec::new();
    for row in 0..height {
        for col in 0..width {
            // Multiples of 1/8: exact in float32 and float64 alike.
            log_odds.push((row * 10 + col) as f32 / 8.0 - 1.0);
            known.push(row != col);
        }
    }
    Raster {
        width,
        height,
        resolution: 0.05,
        origin: Point2::new(-5.0, -2.5),
        first_cell: CellIndex { x: -100, y: -50 },
        log_odds,
        known,
        params: OccupancyParams::default(),
    }
}

#[test]
fn header_is_aligned_and_exact() {
    let data = [0f32; 6];
    let a = NpyArray::new(&[2, 3], NpyData::F32(&data)).unwrap();
    let h = a.header();
    assert_eq!(h.len() % 64, 0);
    assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
    assert_eq!(u16::from_le_bytes([h[8], h[9]]) as usize, h.len() - 10);
    let text = std::str::from_utf8(&h[10..]).unwrap();
    assert!(text.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"));
    assert!(text.ends_with(" \n"));
    let s = [1.0f64];
    let h0 = NpyArray::new(&[], NpyData::F64(&s)).unwrap().header();
    assert!(std::str::from_utf8(&h0[10..]).unwrap().contains("'shape': (), }"));
    let h1 = NpyArray::new(&[1], NpyData::F64(&s)).unwrap().header();
    assert!(std::str::from_utf8(&h1[10..]).unwrap().contains("'shape': (1,), }"));
    assert!(NpyArray::new(&[2, 2], NpyData::F32(&data)).is_none());
    assert!(NpyArray::new(&[usize::MAX, 2], NpyData::F32(&data)).is_none());
}

#[test]
fn map_round_trips() {
    let d = temp_dir("rt");
    let p = d.join("map.npz");
    let r = raster();
    write_map_npz(&p, &r).unwrap();
    let (shape, lo) = read_npz_f32(&p, "log_odds").unwrap();
    assert_eq!(shape, [3, 4]);
    assert_eq!(lo, r.log_odds);
    // Row-major, row = y index: element [2, 1] is row 2, column 1.
    assert_eq!(lo[2 * 4 + 1], 21.0 / 8.0 - 1.0);
    let (shape, occ) = read_npz_f32(&p, "occupancy.npy").unwrap();
    assert_eq!(shape, [3, 4]);
    assert_eq!(occ, r.occupancy());
    let known = read_npz(&p, "known").unwrap();
    assert_eq!(known.shape, [3, 4]);
    assert_eq!(known.values, NpyValues::Bool(r.known.clone()));
    let res = read_npz(&p, "resolution").unwrap();
    assert_eq!(res.shape, Vec::<usize>::new());
    assert_eq!(res.values, NpyValues::F64(vec![0.05]));
    let origin = read_npz(&p, "origin").unwrap();
    assert_eq!(origin.shape, [2]);
    assert_eq!(origin.values, NpyValues::F64(vec![-5.0, -2.5]));
    // Wrong type and missing arrays are errors naming the array.
    let e = read_npz_f32(&p, "known").unwrap_err();
    assert!(e.to_string().contains("`known`"), "{e}");
    let e = read_npz_f32(&p, "nope").unwrap_err();
    assert!(e.to_string().contains("`nope`"), "{e}");
    // Same map, same bytes.
    let p2 = d.join("again.npz");
    write_map_npz(&p2, &r).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), std::fs::read(&p2).unwrap());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn members_are_stored_like_np_savez() {
    let d = temp_dir("stored");
    let p = d.join("map.npz");
    write_map_npz(&p, &raster()).unwrap();
    let mut z = ZipArchive::new(File::open(&p).unwrap()).unwrap();
    let mut names = Vec::new();
    for i in 0..z.len() {
        let f = z.by_index(i).unwrap();
        assert_eq!(f.compression(), CompressionMethod::Stored);
        names.push(f.name().unwrap().to_string());
    }
    assert_eq!(names, ["occupancy.npy", "log_odds.npy", "known.npy", "resolution.npy", "origin.npy"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bad_inputs_are_errors() {
    let d = temp_dir("bad");
    let p = d.join("not.npz");
    std::fs::write(&p, b"hello").unwrap();
    assert!(matches!(read_npz(&p, "x"), Err(Error::Format { location: Location::File, .. })));
    assert!(matches!(read_npz(&d.join("missing.npz"), "x"), Err(Error::Io { .. })));
    let mut r = raster();
    r.known.pop();
    let e = write_map_npz(&d.join("m.npz"), &r).unwrap_err();
    assert!(e.to_string().contains("known flags"), "{e}");
    assert!(!d.join("m.npz").exists());
    let mut w = NpzWriter::new(io::Cursor::new(Vec::new()));
    let one = [1u8];
    let a = NpyArray::new(&[1], NpyData::U8(&one)).unwrap();
    w.add("a", &a).unwrap();
    assert!(w.add("a", &a).is_err());
    assert!(w.add("x/y", &a).is_err());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn header_parser_accepts_numpys_spellings() {
    let (d, f, s) = parse_header("{'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }   \n").unwrap();
    assert_eq!((d.as_str(), f, s), ("<f8", false, vec![3, 4]));
    let (_, _, s) = parse_header("{'descr': '|b1', 'fortran_order': True, 'shape': (7,), }").unwrap();
    assert_eq!(s, [7]);
    let (_, _, s) = parse_header("{'descr': '<f4', 'fortran_order': False, 'shape': (), }").unwrap();
    assert!(s.is_empty());
    assert!(parse_header("{'descr': '<f4'}").is_err());
    assert!(parse_header("nonsense").is_err());
    assert!(parse_header("{'descr': '<f4', 'fortran_order': 0, 'shape': ()}").is_err());
    assert!(parse_header("{'descr': '<f4', 'fortran_order': False, 'shape': (x,)}").is_err());
}

/// NumPy itself loads the file with the documented names, shapes, dtypes and values.
#[test]
fn numpy_loads_the_map() {
    let d = temp_dir("numpy");
    let p = d.join("map.npz");
    let r = raster();
    write_map_npz(&p, &r).unwrap();
    let script = r#"
import sys
import numpy as np
m = np.load(sys.argv[1])
assert sorted(m.files) == ['known', 'log_odds', 'occupancy', 'origin', 'resolution'], m.files
for k in ('occupancy', 'log_odds'):
    assert m[k].dtype == np.float32 and m[k].shape == (3, 4), (k, m[k].dtype, m[k].shape)
assert m['known'].dtype == np.bool_ and m['known'].shape == (3, 4)
assert m['resolution'].dtype == np.float64 and m['resolution'].shape == ()
assert float(m['resolution']) == 0.05
assert m['origin'].dtype == np.float64 and m['origin'].tolist() == [-5.0, -2.5]
lo = m['log_odds']
for iy in range(3):
    for ix in range(4):
        assert lo[iy, ix] == np.float32((iy * 10 + ix) / 8.0 - 1.0), (iy, ix, lo[iy, ix])
        assert m['known'][iy, ix] == (iy != ix)
occ = 1.0 - 1.0 / (1.0 + np.exp(lo.astype(np.float64)))
assert np.allclose(m['occupancy'], occ, atol=1e-6)
print('ok')
"#;
    let out = match std::process::Command::new("python3").arg("-c").arg(script).arg(&p).output() {
        Ok(o) => o,
        Err(e) => {
            crate::testdata::skip(&format!("python3 is not available ({e})"));
            return;
        }
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && stderr.contains("No module named 'numpy'") {
        crate::testdata::skip("numpy is not installed for python3");
        return;
    }
    assert!(out.status.success(), "numpy could not read the file:\n{stderr}");
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "ok");
    std::fs::remove_dir_all(&d).unwrap();
}
