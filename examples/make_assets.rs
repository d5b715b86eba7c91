//! Writes the textures the project's scenes use (run: `cargo run --example make_assets`).
//!
//! `assets/checker.png`: 64x64, an 8x8 checker whose quadrants are tinted (top-left red,
//! top-right green, bottom-left blue, bottom-right yellow) and whose corner cells carry
//! a dark dot, so a render shows at a glance whether u and v run the right way.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let size = 64u32;
    let cell = size / 8;
    let img = image::RgbImage::from_fn(size, size, |x, y| {
        let (cx, cy) = (x / cell, y / cell);
        let light = (cx + cy) % 2 == 0;
        let tint: [f32; 3] = match (cx < 4, cy < 4) {
            (true, true) => [1.0, 0.35, 0.35],
            (false, true) => [0.35, 1.0, 0.35],
            (true, false) => [0.35, 0.45, 1.0],
            (false, false) => [1.0, 0.9, 0.3],
        };
        let base = if light { 0.95 } else { 0.45 };
        let corner = (cx == 0 || cx == 7) && (cy == 0 || cy == 7);
        let (px, py) = (x % cell, y % cell);
        let dot = corner && (2..6).contains(&px) && (2..6).contains(&py);
        let v = |t: f32| if dot { 20 } else { (255.0 * base * t) as u8 };
        image::Rgb([v(tint[0]), v(tint[1]), v(tint[2])])
    });
    img.save("assets/checker.png")?;
    println!("wrote assets/checker.png");
    Ok(())
}
