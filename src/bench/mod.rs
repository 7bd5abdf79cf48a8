//! Benchmarks: every figure they time, they also check (tinybvh's rule), and their
//! JSON says whether all checks passed.

pub mod lbvh;
pub mod modes;
pub mod reflect;
