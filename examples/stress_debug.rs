use glint::stress::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).unwrap();
    let r = render_ron(&text).unwrap();
    for y in 0..r.height {
        let mut line = String::new();
        for x in 0..r.width {
            let v = r.image[(y * r.width + x) as usize];
            line += &format!("{:.3} ", v.x);
        }
        println!("{line}");
    }
}
