//! Frames and rigid transforms.
//!
//! Names say which frame a value lives in and which way a transform maps:
//! `world_from_base * point_in_base == point_in_world` (the convention of rerun and Drake).
//! The grid is 2D, so the pipeline works in SE(2); a sensor's full 3D mounting pose is
//! reduced to the planar transform once, by [`Mount3::to_planar`].

pub mod geodetic;
mod mount;
mod pose2;
mod pose3;

pub use geodetic::{ecef_to_geodetic, geodetic_to_ecef, Datum, GeodeticError};
pub use mount::{quaternion_to_rpy, quaternion_yaw, Mount3, MountError, PlanarMount};
pub use pose2::{normalize_angle, Point2, Pose2, MAX_POSITION_M};
pub use pose3::Pose3;
