//! Integration tests of fusemap-core: one test binary with a module per area, so it links
//! once (`cargo test -p fusemap-core --test core [module::]`).

mod corridor;
mod invalid_returns;
mod sync;
