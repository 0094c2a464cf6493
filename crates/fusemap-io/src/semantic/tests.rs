use super::*;
use crate::npz::{read_npz, write_map_npz_with, NpyValues, NpzLayers};
use fusemap_core::geometry::Point2;
use fusemap_core::grid::{CellIndex, OccupancyParams, Raster};

fn temp_dir(tag: &str) -> crate::testdata::TestDir {
    crate::testdata::temp_dir(&format!("semantic-{tag}"))
}

fn classes() -> Vec<ClassInfo> {
    vec![
        ClassInfo { id: 1, name: "floor".into(), color: [170, 170, 170] },
        ClassInfo { id: 2, name: "wall".into(), color: [90, 90, 200] },
        ClassInfo { id: 6, name: "person: moving".into(), color: [230, 40, 40] },
    ]
}

/// 4 columns × 3 rows. Row 0 (lowest y): floor, wall, unknown, person; row 1: all wall;
/// row 2: unknown, floor, floor, wall. Probabilities encode the cell, the per-class ones
/// the cell and class.
fn semantic() -> SemanticRaster {
    let best = vec![0, 1, -1, 2, 1, 1, 1, 1, -1, 0, 0, 1];
    let prob = (0..12).map(|i| 0.5 + i as f32 / 32.0).collect();
    let probs = (0..12 * 3).map(|j| j as f32 / 64.0).collect();
    SemanticRaster {
        width: 4,
        height: 3,
        resolution: 0.05,
        origin: [-5.0, -2.5],
        classes: classes(),
        best,
        prob,
        probs,
    }
}

fn dynamic() -> CellRaster<f32> {
    CellRaster {
        width: 4,
        height: 3,
        resolution: 0.05,
        origin: Point2::new(-5.0, -2.5),
        first_cell: CellIndex { x: -100, y: -50 },
        cells: vec![0.0, 1.0, 0.5, 0.2, f32::NAN, 0.9, 0.1, 0.3, 0.0, 0.0, 0.0, 0.75],
        known: vec![true, true, true, true, true, true, true, true, false, false, true, true],
    }
}

fn raster() -> Raster {
    Raster {
        width: 4,
        height: 3,
        resolution: 0.05,
        origin: Point2::new(-5.0, -2.5),
        first_cell: CellIndex { x: -100, y: -50 },
        log_odds: vec![0.5; 12],
        known: vec![true; 12],
        params: OccupancyParams::default(),
    }
}

/// Decodes a PNG: (width, height, colour type, palette, pixel rows top first).
fn decode_png(path: &Path) -> (u32, u32, png::ColorType, Option<Vec<u8>>, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let info = reader.info().clone();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut buf).unwrap();
    buf.truncate(frame.buffer_size());
    (info.width, info.height, info.color_type, info.palette.map(|p| p.into_owned()), buf)
}

#[test]
fn semantic_png_has_the_class_palette_and_the_top_row_is_the_highest_y() {
    let d = temp_dir("png");
    let yaml = d.join("semantic.yaml");
    let image = write_semantic(&yaml, &semantic()).unwrap();
    assert_eq!(image, d.join("semantic.png"));
    let (w, h, color_type, palette, pixels) = decode_png(&image);
    assert_eq!((w, h, color_type), (4, 3, png::ColorType::Indexed));
    let palette = palette.unwrap();
    assert_eq!(palette, [170, 170, 170, 90, 90, 200, 230, 40, 40, 128, 128, 128]);
    // Top image row = raster row 2; unknown cells are index K = 3.
    assert_eq!(pixels, [3, 0, 0, 1, 1, 1, 1, 1, 0, 1, 3, 2]);
    // Every pixel's colour is its class colour.
    let s = semantic();
    for (row, line) in pixels.chunks(4).enumerate() {
        for (col, &px) in line.iter().enumerate() {
            let b = s.best[(2 - row) * 4 + col];
            let expected = if b < 0 { UNKNOWN_COLOR } else { s.classes[b as usize].color };
            assert_eq!(&palette[3 * px as usize..3 * px as usize + 3], &expected);
        }
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn semantic_yaml_names_image_placement_and_classes() {
    let d = temp_dir("yaml");
    let yaml = d.join("semantic.yaml");
    write_semantic(&yaml, &semantic()).unwrap();
    let text = std::fs::read_to_string(&yaml).unwrap();
    assert_eq!(
        text,
        "image: semantic.png\nresolution: 0.05\norigin: [-5.0, -2.5, 0.0]\nunknown_index: 3\n\
         unknown_color: [128, 128, 128]\nclasses:\n\
         \x20 - index: 0\n    id: 1\n    name: floor\n    color: [170, 170, 170]\n\
         \x20 - index: 1\n    id: 2\n    name: wall\n    color: [90, 90, 200]\n\
         \x20 - index: 2\n    id: 6\n    name: \"person: moving\"\n    color: [230, 40, 40]\n"
    );
    // No classes: every cell is index 0, the unknown one, and the list is empty.
    let none = SemanticRaster { classes: vec![], best: vec![-1; 12], probs: vec![], ..semantic() };
    write_semantic(&yaml, &none).unwrap();
    assert!(std::fs::read_to_string(&yaml)
        .unwrap()
        .contains("unknown_index: 0\nunknown_color: [128, 128, 128]\nclasses: []\n"));
    std::fs::remove_dir_all(&d).unwrap();
}

/// PyYAML reads the description as a document with the documented keys.
#[test]
fn python_yaml_reads_the_description() {
    let Some(python) = crate::testdata::python_with(&["yaml"]) else { return };
    let d = temp_dir("pyyaml");
    let yaml = d.join("semantic.yaml");
    write_semantic(&yaml, &semantic()).unwrap();
    let script = r#"
import sys, yaml
d = yaml.safe_load(open(sys.argv[1]))
assert d['image'] == 'semantic.png' and d['resolution'] == 0.05 and d['origin'] == [-5.0, -2.5, 0.0], d
assert d['unknown_index'] == 3 and d['unknown_color'] == [128, 128, 128]
assert [c['name'] for c in d['classes']] == ['floor', 'wall', 'person: moving']
assert [c['id'] for c in d['classes']] == [1, 2, 6] and [c['index'] for c in d['classes']] == [0, 1, 2]
assert d['classes'][1]['color'] == [90, 90, 200]
print('ok')
"#;
    let out = std::process::Command::new(python).arg("-c").arg(script).arg(&yaml).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn dynamic_png_shades_probability_and_keeps_205_for_unknown() {
    let d = temp_dir("dyn");
    let p = d.join("dynamic.png");
    write_dynamic_png(&p, &dynamic()).unwrap();
    let (w, h, color_type, palette, pixels) = decode_png(&p);
    assert_eq!((w, h, color_type, palette), (4, 3, png::ColorType::Grayscale, None));
    // Top row = raster row 2: unknown, unknown, p = 0, p = 0.75.
    assert_eq!(&pixels[..4], &[205, 205, 255, 64]);
    // Row 1: NaN (drawn unknown), 0.9, 0.1, 0.3; row 0: 0, 1, 0.5 (127.5 rounds up), 0.2.
    assert_eq!(&pixels[4..8], &[205, 26, 230, 179]);
    assert_eq!(&pixels[8..], &[255, 0, 128, 204]);
    assert_eq!(dynamic_shade(50.0 / 255.0, true), 206, "an observed cell never takes the unknown shade");
    assert_eq!(dynamic_shade(2.0, true), 0);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bad_layers_are_refused_and_leave_no_file() {
    let d = temp_dir("bad");
    let yaml = d.join("semantic.yaml");
    let cases = [
        (SemanticRaster { best: vec![0; 11], ..semantic() }, "12 cells but 11 classes"),
        (SemanticRaster { best: vec![3; 12], ..semantic() }, "class 3, not -1 or an index below 3"),
        (SemanticRaster { best: vec![-2; 12], ..semantic() }, "class -2"),
        (SemanticRaster { probs: vec![0.0; 5], ..semantic() }, "5 per-class probabilities"),
        (SemanticRaster { resolution: 0.0, ..semantic() }, "finite placement"),
        (
            SemanticRaster {
                classes: (0..256).map(|i| ClassInfo { id: i, name: format!("c{i}"), color: [0; 3] }).collect(),
                probs: vec![],
                ..semantic()
            },
            "256 classes",
        ),
        (SemanticRaster { width: 0, height: 0, best: vec![], prob: vec![], probs: vec![], ..semantic() }, "empty"),
    ];
    for (s, needle) in cases {
        let e = write_semantic(&yaml, &s).unwrap_err().to_string();
        assert!(e.contains(needle) && e.contains("semantic.yaml"), "{e}");
        let e = write_map_npz_with(&d.join("map.npz"), &raster(), &NpzLayers { semantic: Some(&s), dynamic: None });
        assert!(e.is_err());
    }
    let e = write_semantic(&d.join("semantic.png"), &semantic()).unwrap_err();
    assert!(e.to_string().contains(".png"), "{e}");
    let mut dyn_bad = dynamic();
    dyn_bad.known.pop();
    assert!(write_dynamic_png(&d.join("dynamic.png"), &dyn_bad).is_err());
    // A layer of other cells than the map's is refused by the npz writer.
    let shifted = SemanticRaster { origin: [0.0, 0.0], ..semantic() };
    let e = write_map_npz_with(&d.join("map.npz"), &raster(), &NpzLayers { semantic: Some(&shifted), dynamic: None })
        .unwrap_err();
    assert!(e.to_string().contains("does not cover"), "{e}");
    // Nothing was written, not even a temporary file.
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_failed_write_keeps_the_previous_files() {
    let d = temp_dir("keep");
    let yaml = d.join("semantic.yaml");
    write_semantic(&yaml, &semantic()).unwrap();
    let (png0, yaml0) = (std::fs::read(d.join("semantic.png")).unwrap(), std::fs::read(&yaml).unwrap());
    assert!(write_semantic(&yaml, &SemanticRaster { best: vec![9; 12], ..semantic() }).is_err());
    assert_eq!(std::fs::read(d.join("semantic.png")).unwrap(), png0);
    assert_eq!(std::fs::read(&yaml).unwrap(), yaml0);
    let mut names: Vec<_> = std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name()).collect();
    names.sort();
    assert_eq!(names, ["semantic.png", "semantic.yaml"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn npz_layers_round_trip() {
    let d = temp_dir("npz");
    let p = d.join("map.npz");
    let (s, dy) = (semantic(), dynamic());
    write_map_npz_with(&p, &raster(), &NpzLayers { semantic: Some(&s), dynamic: Some(&dy) }).unwrap();
    let class = read_npz(&p, "semantic_class").unwrap();
    assert_eq!((class.shape, class.values), (vec![3, 4], NpyValues::I16(s.best.clone())));
    let prob = read_npz(&p, "semantic_prob").unwrap();
    assert_eq!((prob.shape, prob.values), (vec![3, 4], NpyValues::F32(s.prob.clone())));
    let probs = read_npz(&p, "semantic_probs").unwrap();
    assert_eq!((probs.shape, probs.values), (vec![3, 4, 3], NpyValues::F32(s.probs.clone())));
    let names = read_npz(&p, "semantic_class_names").unwrap();
    assert_eq!(names.values, NpyValues::Str(vec!["floor".into(), "wall".into(), "person: moving".into()]));
    assert_eq!(read_npz(&p, "semantic_class_ids").unwrap().values, NpyValues::I32(vec![1, 2, 6]));
    let colors = read_npz(&p, "semantic_class_colors").unwrap();
    assert_eq!(colors.shape, [3, 3]);
    assert_eq!(colors.values, NpyValues::U8(vec![170, 170, 170, 90, 90, 200, 230, 40, 40]));
    let NpyValues::F32(dynamic) = read_npz(&p, "dynamic").unwrap().values else { panic!() };
    for ((v, &p), &k) in dynamic.iter().zip(&dy.cells).zip(&dy.known) {
        assert!(if k && !p.is_nan() { *v == p } else { v.is_nan() }, "{v} {p} {k}");
    }
    // Without layers the file is the plain map.
    let plain = d.join("plain.npz");
    write_map_npz_with(&plain, &raster(), &NpzLayers::default()).unwrap();
    assert!(read_npz(&plain, "semantic_class").is_err());
    let q = d.join("q.npz");
    crate::npz::write_map_npz(&q, &raster()).unwrap();
    assert_eq!(std::fs::read(&q).unwrap(), std::fs::read(&plain).unwrap());
    std::fs::remove_dir_all(&d).unwrap();
}

/// NumPy loads the layers with the documented names, dtypes, shapes and values, without
/// `allow_pickle`.
#[test]
fn numpy_loads_the_semantic_and_dynamic_arrays() {
    let Some(python) = crate::testdata::python_with(&["numpy"]) else { return };
    let d = temp_dir("numpy");
    let p = d.join("map.npz");
    let (s, dy) = (semantic(), dynamic());
    write_map_npz_with(&p, &raster(), &NpzLayers { semantic: Some(&s), dynamic: Some(&dy) }).unwrap();
    let script = r#"
import sys
import numpy as np
m = np.load(sys.argv[1])
c = m['semantic_class']
assert c.dtype == np.int16 and c.shape == (3, 4), (c.dtype, c.shape)
assert c.tolist() == [[0, 1, -1, 2], [1, 1, 1, 1], [-1, 0, 0, 1]], c
p = m['semantic_prob']
assert p.dtype == np.float32 and p.shape == (3, 4)
assert p[1, 2] == np.float32(0.5 + 6 / 32)
q = m['semantic_probs']
assert q.dtype == np.float32 and q.shape == (3, 4, 3)
assert q[2, 1, 2] == np.float32(((2 * 4 + 1) * 3 + 2) / 64)
n = m['semantic_class_names']
assert n.dtype.kind == 'U' and n.tolist() == ['floor', 'wall', 'person: moving'], n
assert m['semantic_class_ids'].tolist() == [1, 2, 6]
assert m['semantic_class_colors'].dtype == np.uint8 and m['semantic_class_colors'].shape == (3, 3)
dy = m['dynamic']
assert dy.dtype == np.float32 and dy.shape == (3, 4)
assert np.isnan(dy[2, 0]) and np.isnan(dy[1, 0]) and dy[0, 1] == 1.0 and dy[2, 3] == np.float32(0.75)
names = [str(x) for x in n]
known = c >= 0
assert names[c[0, 3]] == 'person: moving' and known.sum() == 10
print('ok')
"#;
    let out = std::process::Command::new(python).arg("-c").arg(script).arg(&p).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "ok");
    std::fs::remove_dir_all(&d).unwrap();
}
