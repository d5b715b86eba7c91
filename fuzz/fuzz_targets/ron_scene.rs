//! RON scenes through the real loader and one render pass.
#![no_main]

mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::load_and_render("scenes/scene.ron", data);
});
