//! What the three targets share: a scratch folder with the files a fuzzed input may
//! name, and the real load-and-render path glint's binary takes.

use std::path::PathBuf;
use std::sync::OnceLock;

use glint::{Overrides, Renderer};

/// A scratch folder per process, with `assets/checker.png` and `checker.png` (what the
/// seed scenes and models reference) and a small memory limit, so that an input asking
/// for gigabytes is refused quickly rather than exhausting the fuzzer's RSS limit.
pub fn scratch() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        std::env::set_var("GLINT_MAX_MEMORY", "256M");
        let dir = std::env::temp_dir().join(format!("glint-fuzz-{}", std::process::id()));
        let png = include_bytes!("../../assets/checker.png");
        std::fs::create_dir_all(dir.join("scenes")).unwrap();
        std::fs::create_dir_all(dir.join("assets")).unwrap();
        std::fs::write(dir.join("assets/checker.png"), png).unwrap();
        std::fs::write(dir.join("checker.png"), png).unwrap();
        dir
    })
}

/// Writes `data` to `name` in the scratch folder, loads it as glint's binary would, and
/// renders one pass at 4x4. Errors are fine; a panic or abort is a crash.
pub fn load_and_render(name: &str, data: &[u8]) {
    let file = scratch().join(name);
    std::fs::write(&file, data).unwrap();
    let tiny = Overrides {
        width: Some(4),
        height: Some(4),
        seed: None,
        set: vec![],
    };
    if let Ok(mut renderer) = Renderer::from_file(&file, &tiny) {
        let _ = renderer.render_pass(0, &mut |_| {});
    }
}
