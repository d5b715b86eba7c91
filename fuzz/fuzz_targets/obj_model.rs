//! OBJ models through the real importer and one render pass. The input is split at
//! the first `\0\0`: before it the OBJ, after it the `m.mtl` it may use.
#![no_main]

mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let split = data.windows(2).position(|w| w == b"\0\0");
    let (obj, mtl) = match split {
        Some(i) => (&data[..i], &data[i + 2..]),
        None => (data, &b""[..]),
    };
    std::fs::write(common::scratch().join("m.mtl"), mtl).unwrap();
    common::load_and_render("model.obj", obj);
});
