//! The program as a user runs it: the command line, bad input, the setup
//! script, the viewer under Xvfb, RenderDoc captures and the stability report.
//! One of the few test crates (see tests/render/main.rs).

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod cli_numbers;
mod hostile_input;
mod renderdoc;
mod scale;
mod setup_script;
mod stability;
mod viewer;
