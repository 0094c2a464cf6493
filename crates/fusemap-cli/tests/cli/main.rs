//! Integration tests: the `fusemap` binary on real files. One test binary with a module
//! per area, so it links once.

mod bad_input;
mod corpus;
mod demo;
mod doctor;
mod formats;
mod limits;
mod output_set;
mod real_logs;
mod relations;
mod scenario_demo;
mod simulate;
mod sync;
mod tree;
mod util;
mod validate;
