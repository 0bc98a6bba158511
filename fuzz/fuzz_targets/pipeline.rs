//! cargo-fuzz target: see common.rs for what it exercises.
#![no_main]

#[path = "../common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::pipeline(data);
});
