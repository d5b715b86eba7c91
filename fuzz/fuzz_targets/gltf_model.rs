//! glTF and GLB models through the real importer and one render pass.
#![no_main]

mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(b"glTF") {
        "model.glb"
    } else {
        "model.gltf"
    };
    common::load_and_render(name, data);
});
