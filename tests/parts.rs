//! Split renders: parts of sample ranges and crops merge bit-identically into the single
//! render of all their samples, and the merge refuses parts that do not fit together.

mod common;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::process::Command;

use glint::Renderer;
use glint::film::Film;
use glint::film::estimate::EstimateMethod;
use glint::film::part::{
    Crop, Part, merge_into_part, merge_parts, read_part, scene_hash, write_part,
};
use glint::scene::Overrides;

use common::temp_dir;

/// A noisy scene: an area light (soft shadows), reflections, 16 samples per pixel.
fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box_parallelogram_light.ron")
}

const W: u32 = 40;
const H: u32 = 30;
const SPP: u32 = 16;

fn overrides(stratified: bool) -> Overrides {
    let mut set = vec![("pixel_samples".to_owned(), SPP.to_string())];
    if stratified {
        set.push(("pixel_sampling".into(), "stratified".into()));
    }
    Overrides {
        width: Some(W),
        height: Some(H),
        seed: Some(7),
        set,
    }
}

fn single(stratified: bool) -> Film {
    let mut r = Renderer::from_file(&scene(), &overrides(stratified)).unwrap();
    r.render(None, &mut |_| {}).unwrap();
    r.film().clone()
}

fn part(stratified: bool, samples: Range<u32>, crop: Crop) -> (PathBuf, Part) {
    let mut r = Renderer::from_file(&scene(), &overrides(stratified)).unwrap();
    let s = r.render_part(samples.clone(), crop, &mut |_| {}).unwrap();
    assert!(!s.interrupted);
    let name = format!("{}..{}@{crop}.exr", samples.start, samples.end);
    (name.into(), r.part("hash".into(), samples, crop))
}

fn crop(x0: u32, y0: u32, x1: u32, y1: u32) -> Crop {
    Crop { x0, y0, x1, y1 }
}

/// The images' bits, so that a difference in the last bit of one pixel fails.
fn bits(film: &Film) -> Vec<[u32; 3]> {
    film.image()
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

fn merged(parts: &[(PathBuf, Part)]) -> Film {
    let (film, samples) = merge_parts(parts).unwrap();
    assert_eq!(samples, 0..SPP);
    film
}

#[test]
fn sample_splits_merge_bit_identically() {
    let full = Crop::full(W, H);
    for stratified in [false, true] {
        let expected = bits(&single(stratified));
        for cuts in [&[][..], &[1], &[5, 9], &[7, 8, 15], &[2, 3, 4, 11]] {
            let mut edges = vec![0];
            edges.extend_from_slice(cuts);
            edges.push(SPP);
            // Merged in reverse order: the order of the parts does not matter either.
            let parts: Vec<_> = edges
                .windows(2)
                .rev()
                .map(|e| part(stratified, e[0]..e[1], full))
                .collect();
            assert!(
                bits(&merged(&parts)) == expected,
                "split at {cuts:?} (stratified {stratified}) differs from the single render"
            );
        }
    }
}

#[test]
fn crop_tilings_merge_bit_identically() {
    let expected = bits(&single(false));
    let tilings: [&[Crop]; 3] = [
        &[crop(0, 0, W, 13), crop(0, 13, W, H)],
        &[
            crop(0, 0, 17, 11),
            crop(17, 0, W, 11),
            crop(0, 11, 3, H),
            crop(3, 11, W, H),
        ],
        &[crop(0, 0, 1, 1), crop(1, 0, W, 1), crop(0, 1, W, H)],
    ];
    for tiles in tilings {
        let parts: Vec<_> = tiles.iter().map(|&c| part(false, 0..SPP, c)).collect();
        assert!(
            bits(&merged(&parts)) == expected,
            "tiling {tiles:?} differs"
        );
    }
    // Crops and sample ranges at once: half the samples whole, the rest in two windows.
    let parts = [
        part(false, 0..6, Crop::full(W, H)),
        part(false, 6..SPP, crop(0, 0, 25, H)),
        part(false, 6..SPP, crop(25, 0, W, H)),
    ];
    assert!(bits(&merged(&parts)) == expected);
}

#[test]
fn merges_of_merges_are_bit_identical() {
    let expected = bits(&single(false));
    // A tree: (3..9 in two windows + 9..16) as one part, then with 0..3.
    let inner = [
        part(false, 3..9, crop(0, 0, W, 7)),
        part(false, 3..9, crop(0, 7, W, H)),
        part(false, 9..SPP, Crop::full(W, H)),
    ];
    let later = merge_into_part(&inner).unwrap();
    assert_eq!(later.info.samples, 3..SPP);
    let parts = [part(false, 0..3, Crop::full(W, H)), ("later".into(), later)];
    assert!(bits(&merged(&parts)) == expected);
}

#[test]
fn parts_survive_their_files_bit_for_bit() {
    let dir = temp_dir();
    let (name, p) = part(false, 3..11, crop(5, 4, 33, 29));
    let path = dir.path().join(&name);
    write_part(&path, &p).unwrap();
    let back = read_part(&path).unwrap();
    assert_eq!(back.info, p.info);
    let same = |a: &[glam::DVec3], b: &[glam::DVec3]| {
        a.iter()
            .zip(b)
            .all(|(x, y)| x.to_array().map(f64::to_bits) == y.to_array().map(f64::to_bits))
    };
    assert!(same(&back.film.sum, &p.film.sum) && same(&back.film.err, &p.film.err));
    assert_eq!(back.film.count, p.film.count);
    // Written twice, the same bytes.
    let again = dir.path().join("again.exr");
    write_part(&again, &p).unwrap();
    assert!(std::fs::read(&path).unwrap() == std::fs::read(&again).unwrap());
}

/// A merged image estimates its own error as a single render does: the moments and the
/// odd replica travel with the parts (the moments merge by Chan's pairwise update), and
/// survive the part files' f32 channels.
#[test]
fn merged_parts_carry_the_error_estimate() {
    let dir = temp_dir();
    for sampler in ["independent", "sobol"] {
        let overrides = || {
            let mut o = overrides(false);
            o.set.push(("sampler".into(), sampler.into()));
            o
        };
        let mut r = Renderer::from_file(&scene(), &overrides()).unwrap();
        r.render(None, &mut |_| {}).unwrap();
        let method = EstimateMethod::for_settings(r.settings());
        let expected = r.film().error_estimate(method).unwrap();
        let parts: Vec<_> = [0..5, 5..6, 6..SPP]
            .into_iter()
            .map(|samples| {
                let mut r = Renderer::from_file(&scene(), &overrides()).unwrap();
                r.render_part(samples.clone(), Crop::full(W, H), &mut |_| {})
                    .unwrap();
                let path = dir.path().join(format!("{sampler}{}.exr", samples.start));
                write_part(&path, &r.part("hash".into(), samples, Crop::full(W, H))).unwrap();
                (path.clone(), read_part(&path).unwrap())
            })
            .collect();
        let got = merged(&parts).error_estimate(method).unwrap();
        for (what, g, e) in [
            ("RMSE", got.rmse, expected.rmse),
            ("relMSE", got.rel_mse, expected.rel_mse),
        ] {
            assert!(
                e > 0.0 && (g / e - 1.0).abs() < 1e-5,
                "{sampler} {what}: {g} vs {e}"
            );
        }
    }
}

/// Measures how often a pixel's plain `f64` sum (what the film held before it kept the
/// rounding error) is rounded, so that adding parts' plain sums could differ; prints it.
#[test]
fn how_often_plain_f64_sums_round() {
    let parts = [
        part(false, 0..5, Crop::full(W, H)),
        part(false, 5..SPP, Crop::full(W, H)),
    ];
    let film = single(false);
    let inexact = film.err.iter().filter(|e| **e != glam::DVec3::ZERO).count();
    let differ = (0..film.sum.len())
        .filter(|&i| film.sum[i] != parts[0].1.film.sum[i] + parts[1].1.film.sum[i])
        .count();
    println!(
        "{W}x{H} at {SPP} spp: {inexact} pixels with a rounded f64 sum, {differ} whose plain sum of two parts differs"
    );
    assert!(bits(&merged(&parts)) == bits(&film));
}

#[test]
fn the_merge_refuses_parts_that_do_not_fit() {
    let full = Crop::full(W, H);
    let a = part(false, 0..8, full);
    let b = part(false, 8..SPP, full);
    let error = |parts: Vec<(PathBuf, Part)>| merge_parts(&parts).unwrap_err().to_string();

    let overlap = part(false, 6..SPP, full);
    let e = error(vec![a.clone(), overlap]);
    assert!(e.starts_with("6..16@") && e.contains("overlap"), "{e}");

    let gap = part(false, 9..SPP, full);
    let e = error(vec![a.clone(), gap]);
    assert!(
        e.starts_with("9..16@") && e.contains("no part has its samples 8..9"),
        "{e}"
    );

    let half = part(false, 8..SPP, crop(0, 0, W, 10));
    let e = error(vec![a.clone(), half]);
    assert!(e.contains("do not tile the image"), "{e}");

    let mut other_scene = b.clone();
    other_scene.0 = "other_scene.exr".into();
    other_scene.1.info.scene_hash = "different".into();
    let e = error(vec![a.clone(), other_scene]);
    assert!(
        e.starts_with("other_scene.exr: the scene's contents differ"),
        "{e}"
    );

    let mut r = Renderer::from_file(&scene(), &{
        let mut o = overrides(false);
        o.seed = Some(8);
        o
    })
    .unwrap();
    r.render_part(8..SPP, full, &mut |_| {}).unwrap();
    let e = error(vec![
        a.clone(),
        ("seed8.exr".into(), r.part("hash".into(), 8..SPP, full)),
    ]);
    assert!(e.starts_with("seed8.exr: the settings differ"), "{e}");

    assert_eq!(merge_parts(&[a, b]).unwrap().1, 0..SPP);
}

#[test]
fn the_scene_hash_follows_the_files_a_scene_names() {
    let dir = temp_dir();
    // In a subfolder: the scene names its texture as `../assets/...`.
    std::fs::create_dir(dir.path().join("scenes")).unwrap();
    let scene = dir.path().join("scenes/s.ron");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cube_textured.ron"),
    )
    .unwrap();
    let texture = text
        .split("kd_texture: Some(\"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .expect("the scene names a texture")
        .to_owned();
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(&texture);
    let dst = dir.path().join("scenes").join(&texture);
    std::fs::create_dir_all(dst.parent().unwrap()).unwrap();
    std::fs::copy(&src, &dst).unwrap();
    std::fs::write(&scene, &text).unwrap();
    let before = scene_hash(&scene).unwrap();
    assert_eq!(before, scene_hash(&scene).unwrap());
    let mut bytes = std::fs::read(&dst).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&dst, bytes).unwrap();
    assert_ne!(before, scene_hash(&scene).unwrap());
}

fn glint(dir: &Path, args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn the_cli_merges_parts_into_the_bytes_of_a_single_render() {
    let dir = temp_dir();
    let d = dir.path();
    let scene = scene();
    let scene = scene.to_str().unwrap();
    let common = [
        "--width",
        "40",
        "--height",
        "30",
        "--set",
        "pixel_samples=16",
        "-q",
    ];
    let render = |extra: &[&str]| {
        let mut args = vec!["render", scene];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        let (ok, err) = glint(d, &args);
        assert!(ok, "{args:?}: {err}");
    };
    render(&["-o", "single.png"]);
    render(&["-o", "single.exr"]);
    render(&["--samples", "0..3", "-o", "p1.exr"]);
    render(&["--samples", "3..16", "--crop", "0,0,40,20", "-o", "p2.exr"]);
    render(&["--samples", "3..16", "--crop", "0,20,40,30", "-o", "p3.exr"]);
    for out in ["merged.png", "merged.exr"] {
        let (ok, err) = glint(d, &["merge", "p3.exr", "p1.exr", "p2.exr", "-o", out]);
        assert!(ok, "{err}");
        let single = out.replace("merged", "single");
        assert!(
            std::fs::read(d.join(out)).unwrap() == std::fs::read(d.join(single)).unwrap(),
            "{out} differs from the single render"
        );
        assert!(!err.contains("warning"), "{err}");
    }
    // Fewer samples than the scene's pixel_samples merge, with a warning that says so.
    let (ok, err) = glint(d, &["merge", "p1.exr", "-o", "few.png"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: the parts hold samples 0..3 of the 16"),
        "{err}"
    );
    // Refusals: one line naming the file, exit code 1.
    for (args, named, why) in [
        (
            &["merge", "p1.exr", "p2.exr", "-o", "x.png"][..],
            "p1.exr",
            "do not tile",
        ),
        (
            &[
                "merge", "p1.exr", "p2.exr", "p3.exr", "p2.exr", "-o", "x.png",
            ],
            "p2.exr",
            "overlap",
        ),
        (
            &["merge", "p1.exr", "single.exr", "-o", "x.png"],
            "single.exr",
            "not a glint part",
        ),
        (
            &["merge", "p1.exr", "single.png", "-o", "x.png"],
            "single.png",
            "not a readable EXR",
        ),
        (
            &["merge", "p1.exr", "missing.exr", "-o", "x.png"],
            "missing.exr",
            "",
        ),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_glint"))
            .current_dir(d)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with(&format!("error: {named}: ")) && err.contains(why),
            "{err}"
        );
    }
    // A merge into a part merges again; an image needs samples from 0.
    let (ok, err) = glint(
        d,
        &["merge", "p2.exr", "p3.exr", "--part", "-o", "late.exr"],
    );
    assert!(ok, "{err}");
    let (ok, err) = glint(d, &["merge", "late.exr", "-o", "x.png"]);
    assert!(!ok && err.contains("no part has samples 0..3"), "{err}");
    let (ok, err) = glint(d, &["merge", "late.exr", "p1.exr", "-o", "tree.exr"]);
    assert!(ok, "{err}");
    assert!(
        std::fs::read(d.join("tree.exr")).unwrap() == std::fs::read(d.join("single.exr")).unwrap()
    );
    assert!(!d.join("x.png").exists());
    // A part is EXR, within the render's samples and inside the image.
    for (extra, why) in [
        (&["--samples", "0..4", "-o", "p.png"][..], "written as EXR"),
        (
            &["--samples", "0..17", "-o", "p.exr"],
            "the render takes samples 0..16",
        ),
        (
            &["--crop", "0,0,41,30", "-o", "p.exr"],
            "not a non-empty window",
        ),
        (&["--samples", "4..4", "-o", "p.exr"], "must not be empty"),
    ] {
        let mut args = vec!["render", scene];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        let (ok, err) = glint(d, &args);
        assert!(!ok && err.contains(why), "{extra:?}: {err}");
    }
}
