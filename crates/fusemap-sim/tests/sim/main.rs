//! Integration tests of fusemap-sim: the core's models on simulated recordings, one test
//! binary with a module per area (`cargo test -p fusemap-sim --test sim [module::]`).

mod lidar_faults;
