//! Integration tests of fusemap-pipeline: one test binary with a module per area, so it links
//! once (`cargo test -p fusemap-pipeline --test pipeline [module::]`).

mod bad_pose_sensors;
mod calibration;
mod camera_bad_input;
mod camera_scenario;
mod frames;
mod hour_loop;
mod implausible_pose_sensors;
mod production_line;
mod report;
mod scan_angles;
mod scan_frames;
mod sensors;
mod slam_bench;
mod slam_benchmark;
mod validation;
