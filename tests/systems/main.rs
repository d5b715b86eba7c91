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
