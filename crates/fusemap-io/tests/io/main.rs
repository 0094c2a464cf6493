//! Integration tests of fusemap-io: one test binary with a module per area, so it links
//! once (`cargo test -p fusemap-io --test io [module::]`).

mod camera_fixtures;
mod pose_sensor_fixtures;
mod relation_stamps;
mod ros2_fixtures;
mod ros2_writer_rosbags;
