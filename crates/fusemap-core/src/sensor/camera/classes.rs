//! The semantic classes a label image's ids stand for, with what each means for the map.
//!
//! The design document maps segmentation classes to occupancy probabilities (§3.4:
//! floor 0.2, wall 0.7, person 0.5 "with a reduced update rate"): each class carries the
//! occupancy probability its label suggests, an update weight, whether it moves
//! (`dynamic`: it belongs in the dynamic layer, never in static occupancy, §2.4) and
//! whether it is no evidence at all (`ignore`: unlabelled pixels, the ceiling, the sky).

use serde::{Deserialize, Serialize};

/// The most classes a table may hold: class indices fit a `u8`, and a per-cell
/// distribution over the classes stays small.
pub const MAX_CLASSES: usize = 64;

/// One semantic class.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassSpec {
    /// The id label images carry for it.
    pub id: u16,
    /// Its name (unique in a table), as the simulator's world objects and reports use it.
    pub name: String,
    /// Its colour in the semantic picture, RGB.
    pub color: [u8; 3],
    /// The occupancy probability its label suggests, in (0, 1).
    pub p_occupied: f64,
    /// Its update weight, ≥ 0 (the document's "reduced update rate" is a weight below 1).
    pub weight: f64,
    /// It moves (a person, a forklift): it writes the dynamic layer, never static
    /// occupancy.
    pub dynamic: bool,
    /// Not evidence of anything (unlabelled, ceiling, sky): its pixels are counted and
    /// skipped.
    pub ignore: bool,
}

/// Classes indexed densely `0..len()` in table order; [`ClassTable::index_of`] maps a
/// label id to its index. Built only by [`ClassTable::new`], so ids and names are unique,
/// probabilities in (0, 1), weights finite and ≥ 0, and at most [`MAX_CLASSES`].
#[derive(Clone, Debug, PartialEq)]
pub struct ClassTable {
    classes: Vec<ClassSpec>,
    /// `lookup[id]` is the index of the class with label id `id`, or [`NO_CLASS`]; as long
    /// as the largest id + 1 (at most 65,536 bytes), so a pixel's class is one load.
    lookup: Vec<u8>,
}

const NO_CLASS: u8 = u8::MAX;

impl ClassTable {
    /// A table from its classes, checked. The error names the class by position and
    /// field: `class[2].p_occupied: …`.
    pub fn new(classes: Vec<ClassSpec>) -> Result<ClassTable, String> {
        if classes.len() > MAX_CLASSES {
            return Err(format!("class: {} classes, at most {MAX_CLASSES} are supported", classes.len()));
        }
        for (i, c) in classes.iter().enumerate() {
            if let Some(j) = classes[..i].iter().position(|o| o.id == c.id) {
                return Err(format!("class[{i}].id: {} is also the id of class[{j}] (`{}`)", c.id, classes[j].name));
            }
            if c.name.trim().is_empty() {
                return Err(format!("class[{i}].name: must not be empty"));
            }
            if let Some(j) = classes[..i].iter().position(|o| o.name == c.name) {
                return Err(format!("class[{i}].name: `{}` is also the name of class[{j}]", c.name));
            }
            if !c.p_occupied.is_finite() || c.p_occupied <= 0.0 || c.p_occupied >= 1.0 {
                return Err(format!(
                    "class[{i}].p_occupied: must be a probability strictly between 0 and 1, got {}",
                    c.p_occupied
                ));
            }
            if !c.weight.is_finite() || c.weight < 0.0 {
                return Err(format!("class[{i}].weight: must be a finite number >= 0, got {}", c.weight));
            }
        }
        Ok(ClassTable::build(classes))
    }

    /// The table of checked classes (at most [`MAX_CLASSES`], unique ids).
    fn build(classes: Vec<ClassSpec>) -> ClassTable {
        let size = classes.iter().map(|c| c.id as usize + 1).max().unwrap_or(0);
        let mut lookup = vec![NO_CLASS; size];
        for (i, c) in classes.iter().enumerate() {
            // i < MAX_CLASSES = 64 < NO_CLASS.
            lookup[c.id as usize] = i as u8;
        }
        ClassTable { classes, lookup }
    }

    /// The production line's classes (ids as the simulator writes them in label images):
    ///
    /// | id | name | p_occupied | weight | |
    /// |---|---|---|---|---|
    /// | 0 | unlabeled | 0.5 | 0 | ignored |
    /// | 1 | floor | 0.2 | 1 | |
    /// | 2 | wall | 0.7 | 1 | |
    /// | 3 | glass | 0.7 | 1 | |
    /// | 4 | pillar | 0.7 | 1 | |
    /// | 5 | machine | 0.7 | 1 | |
    /// | 6 | person | 0.5 | 0.5 | dynamic |
    /// | 7 | ceiling | 0.5 | 0 | ignored |
    ///
    /// The probabilities are the design document's (§3.4: floor 0.2, wall 0.7, person 0.5
    /// with a reduced rate, here weight 0.5); the other obstacles take the wall's.
    pub fn production_default() -> ClassTable {
        let c = |id: u16, name: &str, color: [u8; 3], p_occupied: f64, weight: f64, dynamic: bool, ignore: bool| {
            ClassSpec { id, name: name.into(), color, p_occupied, weight, dynamic, ignore }
        };
        let classes = vec![
            c(0, "unlabeled", [0, 0, 0], 0.5, 0.0, false, true),
            c(1, "floor", [170, 170, 170], 0.2, 1.0, false, false),
            c(2, "wall", [90, 90, 200], 0.7, 1.0, false, false),
            c(3, "glass", [80, 200, 230], 0.7, 1.0, false, false),
            c(4, "pillar", [230, 150, 40], 0.7, 1.0, false, false),
            c(5, "machine", [60, 170, 60], 0.7, 1.0, false, false),
            c(6, "person", [230, 40, 40], 0.5, 0.5, true, false),
            c(7, "ceiling", [255, 255, 255], 0.5, 0.0, false, true),
        ];
        // Valid as written: `default_table_is_the_interfaces` passes it through `new`.
        ClassTable::build(classes)
    }

    /// The index of the class whose label id is `id`; `None` for an id not in the table.
    #[inline]
    pub fn index_of(&self, id: u16) -> Option<u8> {
        match self.lookup.get(id as usize) {
            Some(&i) if i != NO_CLASS => Some(i),
            _ => None,
        }
    }

    /// The index of the class named `name`.
    pub fn index_by_name(&self, name: &str) -> Option<u8> {
        self.classes.iter().position(|c| c.name == name).map(|i| i as u8)
    }

    /// Number of classes.
    pub fn len(&self) -> usize {
        self.classes.len()
    }

    /// True for a table without classes.
    pub fn is_empty(&self) -> bool {
        self.classes.is_empty()
    }

    /// The class at index `idx` (from [`ClassTable::index_of`]). Panics on an index not
    /// below [`ClassTable::len`]; [`ClassTable::try_get`] does not.
    pub fn get(&self, idx: u8) -> &ClassSpec {
        &self.classes[idx as usize]
    }

    /// The class at index `idx`, `None` when out of range.
    pub fn try_get(&self, idx: u8) -> Option<&ClassSpec> {
        self.classes.get(idx as usize)
    }

    /// Whether a point of class `idx` in the obstacle band claims a static obstacle: a
    /// class that is not dynamic, not ignored and more likely occupied than not (those the
    /// camera's occupancy update makes occupied, see `CameraModel::occupancy_evidence`).
    pub fn is_static_obstacle(&self, idx: u8) -> bool {
        self.try_get(idx).is_some_and(|c| !c.dynamic && !c.ignore && c.p_occupied > 0.5)
    }

    /// The classes in index order.
    pub fn iter(&self) -> std::slice::Iter<'_, ClassSpec> {
        self.classes.iter()
    }

    /// The classes as a slice, in index order.
    pub fn as_slice(&self) -> &[ClassSpec] {
        &self.classes
    }
}

impl Serialize for ClassTable {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.classes.serialize(s)
    }
}

impl<'a> IntoIterator for &'a ClassTable {
    type Item = &'a ClassSpec;
    type IntoIter = std::slice::Iter<'a, ClassSpec>;
    fn into_iter(self) -> Self::IntoIter {
        self.classes.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(id: u16, name: &str) -> ClassSpec {
        ClassSpec {
            id,
            name: name.into(),
            color: [1, 2, 3],
            p_occupied: 0.7,
            weight: 1.0,
            dynamic: false,
            ignore: false,
        }
    }

    #[test]
    fn default_table_is_the_interfaces() {
        let t = ClassTable::production_default();
        assert_eq!(ClassTable::new(t.as_slice().to_vec()).as_ref(), Ok(&t));
        assert_eq!(t.len(), 8);
        let names: Vec<&str> = t.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["unlabeled", "floor", "wall", "glass", "pillar", "machine", "person", "ceiling"]);
        for (i, c) in t.iter().enumerate() {
            assert_eq!(c.id as usize, i);
            assert_eq!(t.index_of(c.id), Some(i as u8));
        }
        assert_eq!(t.get(t.index_by_name("floor").unwrap()).p_occupied, 0.2);
        assert_eq!(t.get(t.index_by_name("wall").unwrap()).p_occupied, 0.7);
        let person = t.get(t.index_by_name("person").unwrap());
        assert!(person.dynamic && person.weight < 1.0 && person.p_occupied == 0.5);
        assert!(t.iter().filter(|c| c.ignore).all(|c| c.weight == 0.0));
        assert_eq!(t.index_of(8), None);
        assert_eq!(t.index_of(u16::MAX), None);
        assert!(t.try_get(8).is_none());
    }

    #[test]
    fn sparse_ids_map_to_dense_indices() {
        let t = ClassTable::new(vec![spec(1000, "a"), spec(3, "b")]).unwrap();
        assert_eq!(t.index_of(1000), Some(0));
        assert_eq!(t.index_of(3), Some(1));
        assert_eq!(t.index_of(4), None);
        assert_eq!(t.index_of(1001), None);
        assert!(ClassTable::new(vec![]).unwrap().is_empty());
        let big = ClassTable::new(vec![spec(u16::MAX, "last")]).unwrap();
        assert_eq!(big.index_of(u16::MAX), Some(0));
    }

    #[test]
    fn bad_tables_name_the_class_and_field() {
        let e = ClassTable::new(vec![spec(1, "a"), spec(1, "b")]).unwrap_err();
        assert!(e.starts_with("class[1].id:") && e.contains("class[0]"), "{e}");
        let e = ClassTable::new(vec![spec(1, "a"), spec(2, "a")]).unwrap_err();
        assert!(e.starts_with("class[1].name:"), "{e}");
        let e = ClassTable::new(vec![spec(1, " ")]).unwrap_err();
        assert!(e.starts_with("class[0].name:"), "{e}");
        for p in [0.0, 1.0, f64::NAN, -0.1] {
            let e = ClassTable::new(vec![ClassSpec { p_occupied: p, ..spec(1, "a") }]).unwrap_err();
            assert!(e.starts_with("class[0].p_occupied:"), "{e}");
        }
        for w in [-1.0, f64::INFINITY, f64::NAN] {
            let e = ClassTable::new(vec![ClassSpec { weight: w, ..spec(1, "a") }]).unwrap_err();
            assert!(e.starts_with("class[0].weight:"), "{e}");
        }
        let many: Vec<ClassSpec> = (0..=MAX_CLASSES as u16).map(|i| spec(i, &format!("c{i}"))).collect();
        assert!(ClassTable::new(many[..MAX_CLASSES].to_vec()).is_ok());
        assert!(ClassTable::new(many).unwrap_err().to_string().contains("at most 64"));
    }
}
