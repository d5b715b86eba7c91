//! `scene::import::guarded` silences only the panics it catches, on its own thread:
//! a panic elsewhere in the process, even during a guarded import, still reaches the
//! hook. (Its own test binary: it installs a process-wide panic hook.)

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use glint::error::GlintError;
use glint::scene::import::guarded;

static REPORTED: AtomicUsize = AtomicUsize::new(0);

#[test]
fn guarded_import_silences_only_its_own_thread() {
    std::panic::set_hook(Box::new(|_| {
        REPORTED.fetch_add(1, Ordering::SeqCst);
    }));
    let result: Result<(), GlintError> = guarded(Path::new("bad.gltf"), "glTF", || {
        // Another thread panics while this import runs: its panic must be reported.
        let other = std::thread::spawn(|| panic!("unrelated"));
        assert!(other.join().is_err());
        panic!("accessor 7 does not exist");
    });
    let message = result.unwrap_err().to_string();
    assert!(message.contains("bad.gltf"), "{message}");
    assert!(message.contains("accessor 7 does not exist"), "{message}");
    assert_eq!(
        REPORTED.load(Ordering::SeqCst),
        1,
        "only the other thread's panic"
    );
    // After the guard, this thread's panics are reported again.
    assert!(std::panic::catch_unwind(|| panic!("after")).is_err());
    assert_eq!(REPORTED.load(Ordering::SeqCst), 2);
}
