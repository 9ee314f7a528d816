//! Measurement against the truth: the path tracer, the report, the
//! attribution of the default frame's error and the ray-traced reference.

#[path = "../common/mod.rs"]
mod common;

mod attribution;
mod glossy;
mod path;
mod prt_report;
mod reference;
mod report;
