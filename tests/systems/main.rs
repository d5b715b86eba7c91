//! One test target for the systems of `schedule.rs`, each run once in a tiny World that
//! holds only what it reads; the tests assert on what it wrote. One module per schedule.

/// A World holding only the given resources.
macro_rules! world {
    ($($resource:expr),* $(,)?) => {{
        let mut world = bevy_ecs::world::World::new();
        $(world.insert_resource($resource);)*
        world
    }};
}

mod bounce;
mod pass;
mod prepare;
mod world;

/// Every system that `schedule.rs` adds has a test here named after it.
#[test]
fn every_scheduled_system_has_a_test() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let schedule = std::fs::read_to_string(root.join("src/schedule.rs")).unwrap();
    let tests: String = ["prepare.rs", "pass.rs", "bounce.rs"]
        .iter()
        .map(|f| std::fs::read_to_string(root.join("tests/systems").join(f)).unwrap())
        .collect();
    // Systems are the snake_case names in `add_systems(..)` that are neither methods
    // (`.in_set`), fields (`p.textures`) nor calls (`planned(..)`).
    let mut systems = Vec::new();
    for block in schedule.split("add_systems(").skip(1) {
        let block = &block[..block.find("));").unwrap_or(block.len())];
        let chars: Vec<char> = block.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            if chars[i].is_ascii_lowercase() && (i == 0 || !is_ident(chars[i - 1])) {
                let start = i;
                while i < chars.len() && is_ident(chars[i]) {
                    i += 1;
                }
                let name: String = chars[start..i].iter().collect();
                let method = start > 0 && chars[start - 1] == '.';
                if name.contains('_') && !method && chars.get(i) != Some(&'(') {
                    systems.push(name);
                }
            } else {
                i += 1;
            }
        }
    }
    assert!(
        systems.len() >= 16,
        "found only {systems:?} in src/schedule.rs"
    );
    let untested: Vec<&String> = systems
        .iter()
        .filter(|s| !tests.contains(&format!("fn {s}_")))
        .collect();
    assert!(untested.is_empty(), "systems without a test: {untested:?}");
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}
