//! WGS84 geodetic coordinates ↔ Earth-centred Earth-fixed (ECEF) ↔ one local
//! East-North-Up (ENU) frame around a datum.
//!
//! fusemap maps in a single local ENU frame (REP 103: x east, y north, z up; REP 105's
//! `map` frame when GNSS anchors it), never in UTM zones: a map crossing a zone border
//! would otherwise have two frames, and UTM's grid convergence and scale factor bend
//! "north" and "metre" away from the ENU of the datum.
//!
//! The maths is the textbook one (Hofmann-Wellenhof, Lichtenegger & Wasle, *GNSS*, §10.2;
//! the same conversions GeographicLib's `Geocentric` and `LocalCartesian` perform):
//! * geodetic → ECEF is closed form, exact;
//! * ECEF → geodetic starts from Bowring's (1976) estimate and refines the latitude by the
//!   fixed-point iteration `φ ← atan2(z + e²·N(φ)·sin φ, p)`, which contracts by about e²
//!   per step and stays well conditioned at the poles; the height uses the form
//!   `h = p·cos φ + z·sin φ − a·√(1 − e²·sin²φ)`, which has no `1/cos φ` singularity.
//!   Three or four steps reach machine precision (far below 1 mm) anywhere near the Earth.

/// WGS84 semi-major axis, metres.
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS84 first eccentricity squared, `f·(2 − f)`.
pub const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);
/// WGS84 semi-minor axis, metres, `a·(1 − f)`.
pub const WGS84_B: f64 = WGS84_A * (1.0 - WGS84_F);

/// Why a datum is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeodeticError {
    /// A coordinate is NaN or infinite.
    #[error("datum `{field}` is not a finite number")]
    NotFinite {
        /// `latitude`, `longitude` or `altitude`.
        field: &'static str,
    },
    /// The latitude lies outside [-90°, 90°].
    #[error("datum latitude {0}° lies outside [-90°, 90°]")]
    Latitude(f64),
}

/// Prime-vertical radius of curvature `N(φ) = a / √(1 − e²·sin²φ)`.
fn prime_vertical_radius(sin_lat: f64) -> f64 {
    WGS84_A / (1.0 - WGS84_E2 * sin_lat * sin_lat).sqrt()
}

/// WGS84 geodetic latitude and longitude (degrees) and ellipsoidal height (metres) to
/// ECEF `[x, y, z]` metres: `x = (N + h)·cos φ·cos λ`, `y = (N + h)·cos φ·sin λ`,
/// `z = (N·(1 − e²) + h)·sin φ`.
pub fn geodetic_to_ecef(lat_deg: f64, lon_deg: f64, alt_m: f64) -> [f64; 3] {
    let (sl, cl) = lat_deg.to_radians().sin_cos();
    let (so, co) = lon_deg.to_radians().sin_cos();
    let n = prime_vertical_radius(sl);
    [(n + alt_m) * cl * co, (n + alt_m) * cl * so, (n * (1.0 - WGS84_E2) + alt_m) * sl]
}

/// ECEF `[x, y, z]` metres to WGS84 (latitude°, longitude°, ellipsoidal height m).
///
/// Bowring's start plus fixed-point refinement (see the module docs). At the Earth's
/// centre, where latitude is undefined, it returns latitude 0 and height `-a`; non-finite
/// input gives NaN, never a panic.
pub fn ecef_to_geodetic(ecef: [f64; 3]) -> (f64, f64, f64) {
    let [x, y, z] = ecef;
    let p = x.hypot(y);
    let lon = y.atan2(x);
    // Bowring's parametric-latitude estimate: exact to ~1e-10 rad at the Earth's surface.
    let ep2 = WGS84_E2 / (1.0 - WGS84_E2);
    let (st, ct) = (z * WGS84_A).atan2(p * WGS84_B).sin_cos();
    let mut lat = (z + ep2 * WGS84_B * st * st * st).atan2(p - WGS84_E2 * WGS84_A * ct * ct * ct);
    for _ in 0..8 {
        let s = lat.sin();
        let next = (z + WGS84_E2 * prime_vertical_radius(s) * s).atan2(p);
        let done = (next - lat).abs() < 1e-15;
        lat = next;
        if done {
            break;
        }
    }
    let (s, c) = lat.sin_cos();
    let h = p * c + z * s - WGS84_A * (1.0 - WGS84_E2 * s * s).sqrt();
    (lat.to_degrees(), lon.to_degrees(), h)
}

/// The origin of a local East-North-Up frame: a WGS84 point and the rotation from ECEF
/// to its tangent plane. `Copy`, computed once, so converting a fix costs a few
/// multiplications.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Datum {
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f64,
    origin_ecef: [f64; 3],
    /// Rows: the east, north and up unit vectors in ECEF.
    enu_from_ecef: [[f64; 3]; 3],
}

impl Datum {
    /// A datum at WGS84 latitude/longitude (degrees) and ellipsoidal height (metres).
    /// Refuses non-finite values and |latitude| > 90°; any finite longitude is accepted
    /// (it wraps).
    pub fn new(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Result<Datum, GeodeticError> {
        for (field, v) in [("latitude", lat_deg), ("longitude", lon_deg), ("altitude", alt_m)] {
            if !v.is_finite() {
                return Err(GeodeticError::NotFinite { field });
            }
        }
        if lat_deg.abs() > 90.0 {
            return Err(GeodeticError::Latitude(lat_deg));
        }
        let (sl, cl) = lat_deg.to_radians().sin_cos();
        let (so, co) = lon_deg.to_radians().sin_cos();
        Ok(Datum {
            lat_deg,
            lon_deg,
            alt_m,
            origin_ecef: geodetic_to_ecef(lat_deg, lon_deg, alt_m),
            enu_from_ecef: [[-so, co, 0.0], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]],
        })
    }

    /// Latitude, degrees.
    pub fn latitude(&self) -> f64 {
        self.lat_deg
    }

    /// Longitude, degrees.
    pub fn longitude(&self) -> f64 {
        self.lon_deg
    }

    /// Ellipsoidal height, metres.
    pub fn altitude(&self) -> f64 {
        self.alt_m
    }

    /// An ECEF point in this datum's ENU frame: `R·(X − X₀)`.
    pub fn ecef_to_enu(&self, ecef: [f64; 3]) -> [f64; 3] {
        let d = [ecef[0] - self.origin_ecef[0], ecef[1] - self.origin_ecef[1], ecef[2] - self.origin_ecef[2]];
        self.enu_from_ecef.map(|r| r[0] * d[0] + r[1] * d[1] + r[2] * d[2])
    }

    /// An ENU point of this datum in ECEF: `X₀ + Rᵀ·enu`.
    pub fn enu_to_ecef(&self, enu: [f64; 3]) -> [f64; 3] {
        let r = &self.enu_from_ecef;
        let mut out = self.origin_ecef;
        for (k, o) in out.iter_mut().enumerate() {
            *o += r[0][k] * enu[0] + r[1][k] * enu[1] + r[2][k] * enu[2];
        }
        out
    }

    /// WGS84 latitude/longitude (degrees) and ellipsoidal height (metres) to
    /// `[east, north, up]` metres in this datum's frame.
    pub fn to_enu(&self, lat_deg: f64, lon_deg: f64, alt_m: f64) -> [f64; 3] {
        self.ecef_to_enu(geodetic_to_ecef(lat_deg, lon_deg, alt_m))
    }

    /// `[east, north, up]` metres in this datum's frame to WGS84 (latitude°, longitude°,
    /// height m).
    pub fn to_geodetic(&self, enu: [f64; 3]) -> (f64, f64, f64) {
        ecef_to_geodetic(self.enu_to_ecef(enu))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn assert_close3(a: [f64; 3], b: [f64; 3], tol: f64) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < tol, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn axes_and_poles() {
        assert_close3(geodetic_to_ecef(0.0, 0.0, 0.0), [WGS84_A, 0.0, 0.0], 1e-6);
        assert_close3(geodetic_to_ecef(0.0, 90.0, 0.0), [0.0, WGS84_A, 0.0], 1e-6);
        assert_close3(geodetic_to_ecef(0.0, 180.0, 10.0), [-WGS84_A - 10.0, 0.0, 0.0], 1e-6);
        assert_close3(geodetic_to_ecef(90.0, 0.0, 0.0), [0.0, 0.0, WGS84_B], 1e-6);
        assert_close3(geodetic_to_ecef(-90.0, 0.0, 100.0), [0.0, 0.0, -WGS84_B - 100.0], 1e-6);
        // The semi-minor axis of WGS84 as published (NIMA TR8350.2, table 3.1).
        assert!((WGS84_B - 6_356_752.314_245).abs() < 1e-3);
        let (lat, _, h) = ecef_to_geodetic([0.0, 0.0, WGS84_B + 5.0]);
        assert!((lat - 90.0).abs() < 1e-12 && (h - 5.0).abs() < 1e-6, "{lat} {h}");
        let (lat, lon, h) = ecef_to_geodetic([WGS84_A + 1.0, 0.0, 0.0]);
        assert!(lat.abs() < 1e-12 && lon.abs() < 1e-12 && (h - 1.0).abs() < 1e-6);
    }

    #[test]
    fn geographiclib_cartconvert_examples() {
        // GeographicLib CartConvert(1), EXAMPLES: `echo 33.3 44.4 6000 | CartConvert`.
        assert_close3(geodetic_to_ecef(33.3, 44.4, 6000.0), [3_816_209.60, 3_737_108.55, 3_485_109.57], 0.006);
        // `echo 33.3 44.4 6000 | CartConvert -l 33 44 20` prints 37288.97 33374.29 5783.64;
        // the same formulas in 40-digit arithmetic give up = 5783.6466, so the printed last
        // digit is 7 mm off and the check allows 1 cm.
        let datum = Datum::new(33.0, 44.0, 20.0).unwrap();
        assert_close3(datum.to_enu(33.3, 44.4, 6000.0), [37_288.97, 33_374.29, 5_783.64], 0.01);
        assert_close3(datum.to_enu(33.3, 44.4, 6000.0), [37_288.973_197, 33_374.294_947, 5_783.646_616], 1e-5);
        // (CartConvert's third example, `30000 30000 0 -r`, lies 6,300 km deep, inside the
        // evolute where several latitudes are valid; this module is for points near the surface.)
        // Mount Everest, as GeographicLib's `Geocentric` gives it.
        assert_close3(geodetic_to_ecef(27.99, 86.93, 8820.0), [302_271.43, 5_635_928.37, 2_979_666.13], 0.006);
    }

    #[test]
    fn hundred_metres_north_drops_below_the_tangent_plane() {
        let datum = Datum::new(48.0, 11.0, 500.0).unwrap();
        // A point on the ellipsoid's surface 100 m north: the tangent plane rises above it by
        // d²/(2R) ≈ 0.78 mm.
        let (lat, lon, alt) = datum.to_geodetic([0.0, 100.0, 0.0]);
        assert!((alt - 500.000_785).abs() < 1e-4, "{alt}");
        let enu = datum.to_enu(lat, lon, 500.0);
        assert!(enu[0].abs() < 1e-6 && (enu[1] - 100.0).abs() < 1e-3, "{enu:?}");
        assert!((enu[2] + 0.000_785).abs() < 1e-4, "{enu:?}");
        assert_close3(datum.to_enu(48.0, 11.0, 500.0), [0.0; 3], 1e-6);
    }

    #[test]
    fn bad_datums_are_refused() {
        assert_eq!(Datum::new(90.5, 0.0, 0.0), Err(GeodeticError::Latitude(90.5)));
        assert_eq!(Datum::new(f64::NAN, 0.0, 0.0), Err(GeodeticError::NotFinite { field: "latitude" }));
        assert_eq!(Datum::new(0.0, f64::INFINITY, 0.0), Err(GeodeticError::NotFinite { field: "longitude" }));
        assert_eq!(Datum::new(0.0, 0.0, f64::NAN), Err(GeodeticError::NotFinite { field: "altitude" }));
        assert!(Datum::new(-90.0, 720.0, -100.0).is_ok());
        let (lat, lon, h) = ecef_to_geodetic([f64::NAN, 0.0, 0.0]);
        assert!(lat.is_nan() || lon.is_nan() || h.is_nan());
    }

    proptest! {
        #[test]
        fn geodetic_ecef_round_trip(lat in -90.0..=90.0f64, lon in -180.0..180.0f64, h in -10_000.0..100_000.0f64) {
            let (la, lo, hh) = ecef_to_geodetic(geodetic_to_ecef(lat, lon, h));
            // 1e-9 degrees of latitude is 0.1 mm on the ground.
            prop_assert!((la - lat).abs() < 1e-9, "{} vs {}", la, lat);
            if lat.abs() < 89.9999 {
                prop_assert!(((lo - lon + 540.0).rem_euclid(360.0) - 180.0).abs() < 1e-9);
            }
            prop_assert!((hh - h).abs() < 1e-4, "{} vs {}", hh, h);
        }

        #[test]
        fn enu_round_trip(lat0 in -89.0..89.0f64, lon0 in -180.0..180.0f64, h0 in -100.0..3000.0f64,
                          e in -5_000.0..5_000.0f64, n in -5_000.0..5_000.0f64, u in -100.0..100.0f64) {
            let datum = Datum::new(lat0, lon0, h0).unwrap();
            let (lat, lon, h) = datum.to_geodetic([e, n, u]);
            let back = datum.to_enu(lat, lon, h);
            prop_assert!((back[0] - e).abs() < 1e-4 && (back[1] - n).abs() < 1e-4 && (back[2] - u).abs() < 1e-4,
                         "{:?} vs {:?}", back, [e, n, u]);
            // The ENU rotation is orthonormal: distances from the datum are preserved in ECEF.
            let x = datum.enu_to_ecef([e, n, u]);
            let o = geodetic_to_ecef(lat0, lon0, h0);
            let d = ((x[0] - o[0]).powi(2) + (x[1] - o[1]).powi(2) + (x[2] - o[2]).powi(2)).sqrt();
            prop_assert!((d - (e * e + n * n + u * u).sqrt()).abs() < 1e-6);
        }
    }
}
