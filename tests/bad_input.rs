//! Bad input: one clear line naming the file, the entity and the field; never a panic;
//! a non-zero exit code and no image from the command line.

mod common;

use std::process::Command;

use common::*;
use tempfile::TempDir;

const GOOD: &str = r#"(
    camera: (position: (0, 0, 3), look_at: (0, 0, 0), fov_y: 40, width: 8, height: 8),
    materials: { "m": (kd: (0.5, 0.5, 0.5)) },
    entities: [
        Sphere((name: Some("ball"), center: (0, 0, 0), radius: 1, material: "m")),
        Mesh((name: Some("tri"), material: Some("m"), geometry: Inline(
            vertices: [(position: (0, 0, 0)), (position: (1, 0, 0)), (position: (0, 1, 0))],
            triangles: [(0, 1, 2)]))),
        PointLight((position: (0, 2, 2), color: (1, 1, 1))),
    ],
)"#;

fn bad(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "{from} not in the scene");
    load_error(&GOOD.replacen(from, to, 1))
}

#[track_caller]
fn assert_mentions(message: &str, parts: &[&str]) {
    assert!(!message.contains('\n'), "not one line: {message}");
    assert!(message.starts_with("tests/bad.ron"), "no file: {message}");
    for p in parts {
        assert!(message.contains(p), "{message:?} does not mention {p:?}");
    }
}

#[test]
fn the_good_scene_loads() {
    load(GOOD);
}

#[test]
fn syntax_errors_give_line_and_column() {
    let m = bad("fov_y: 40,", "fov_y: 40,,");
    assert_mentions(&m, &["tests/bad.ron:2:"]);
}

#[test]
fn unknown_fields_are_errors_with_position() {
    let m = bad("radius: 1,", "radius: 1, radiuss: 2,");
    assert_mentions(&m, &["tests/bad.ron:5:", "radiuss"]);
}

#[test]
fn type_errors_are_errors_with_position() {
    let m = bad("radius: 1,", "radius: \"big\",");
    assert_mentions(&m, &["tests/bad.ron:5:"]);
}

#[test]
fn nan_and_infinite_numbers_are_rejected() {
    assert_mentions(
        &bad("center: (0, 0, 0)", "center: (0, NaN, 0)"),
        &["Sphere \"ball\"", "center", "finite"],
    );
    assert_mentions(
        &bad("position: (0, 2, 2)", "position: (0, inf, 2)"),
        &["PointLight", "position", "finite"],
    );
    assert_mentions(
        &bad("kd: (0.5, 0.5, 0.5)", "kd: (0.5, -inf, 0.5)"),
        &["material \"m\"", "kd"],
    );
}

#[test]
fn zero_or_negative_radius_is_rejected() {
    for r in ["0", "-1"] {
        let m = bad("radius: 1,", &format!("radius: {r},"));
        assert_mentions(&m, &["Sphere \"ball\"", "radius", "positive"]);
    }
}

#[test]
fn zero_field_of_view_is_rejected() {
    assert_mentions(&bad("fov_y: 40", "fov_y: 0"), &["camera", "fov_y"]);
}

#[test]
fn zero_and_absurd_image_sizes_are_rejected() {
    assert_mentions(&bad("width: 8", "width: 0"), &["camera", "width"]);
    assert_mentions(
        &bad("height: 8", "height: 40000"),
        &["camera", "height", "32768"],
    );
}

#[test]
fn out_of_range_triangle_indices_are_rejected() {
    let m = bad("triangles: [(0, 1, 2)]", "triangles: [(0, 1, 3)]");
    assert_mentions(&m, &["Mesh \"tri\"", "triangles[0]", "out of range"]);
}

#[test]
fn unknown_material_names_are_rejected() {
    let m = bad("material: \"m\"", "material: \"chrome\"");
    assert_mentions(&m, &["Sphere \"ball\"", "material", "chrome"]);
}

#[test]
fn degenerate_cameras_and_settings_are_rejected() {
    assert_mentions(
        &bad("look_at: (0, 0, 0)", "look_at: (0, 0, 3)"),
        &["camera", "look_at"],
    );
    assert_mentions(
        &bad("look_at: (0, 0, 0)", "look_at: (0, 0, 0), up: (0, 0, 1)"),
        &["camera", "up", "parallel"],
    );
    assert_mentions(
        &bad("materials:", "settings: (gradient: []), materials:"),
        &["settings", "gradient"],
    );
    assert_mentions(
        &bad("materials:", "settings: (pixel_samples: 0), materials:"),
        &["settings", "pixel_samples"],
    );
    assert_mentions(
        &bad(
            "kd: (0.5, 0.5, 0.5)",
            "kd: (0.5, 0.5, 0.5), transparency: 1.5",
        ),
        &["material \"m\"", "transparency"],
    );
    assert_mentions(
        &bad("kd: (0.5, 0.5, 0.5)", "kd: (0.5, 0.5, 0.5), shininess: -1"),
        &["material \"m\"", "shininess"],
    );
}

/// Runs the real binary in a fresh temporary folder holding `scene.ron`.
fn run_cli(scene: Option<&str>, args: &[&str]) -> (bool, String, TempDir) {
    let dir = match scene {
        Some(s) => scene_dir(s),
        None => temp_dir(),
    };
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.success(), stderr, dir)
}

#[test]
fn the_cli_renders_a_good_scene_and_prints_a_summary() {
    let (ok, stderr, tmp) = run_cli(Some(GOOD), &["render", "scene.ron", "-o", "out.png"]);
    let dir = tmp.path();
    assert!(ok, "{stderr}");
    assert!(stderr.contains("8x8, 1 spp"), "{stderr}");
    assert!(stderr.contains("Mrays/s"), "{stderr}");
    let img = image::open(dir.join("out.png")).unwrap();
    assert_eq!((img.width(), img.height()), (8, 8));
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn the_cli_fails_with_one_line_and_keeps_the_old_image() {
    let broken = GOOD.replacen("radius: 1,", "radius: -1,", 1);
    let (ok, stderr, tmp) = run_cli(Some(&broken), &["render", "scene.ron", "-o", "out.png"]);
    let dir = tmp.path();
    assert!(!ok);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: scene.ron: entities[0]"),
        "{stderr}"
    );
    assert!(!dir.join("out.png").exists());

    // An existing image survives a failing run untouched.
    std::fs::write(dir.join("out.png"), b"previous").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir)
        .args(["render", "scene.ron", "-o", "out.png"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), b"previous");
}

#[test]
fn the_cli_reports_a_missing_scene_file() {
    let (ok, stderr, _) = run_cli(None, &["render", "missing.ron"]);
    assert!(!ok);
    assert!(stderr.starts_with("error: missing.ron:"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1);
}

#[test]
fn the_cli_rejects_unknown_settings_and_output_formats() {
    let (ok, stderr, _) = run_cli(Some(GOOD), &["render", "scene.ron", "--set", "shadow=on"]);
    assert!(!ok);
    assert!(stderr.contains("unknown setting \"shadow\""), "{stderr}");
    let (ok, stderr, _) = run_cli(Some(GOOD), &["render", "scene.ron", "-o", "out.jpg"]);
    assert!(!ok);
    assert!(stderr.contains("unknown output format"), "{stderr}");
    let (ok, stderr, _) = run_cli(
        Some(GOOD),
        &["render", "scene.ron", "-o", "no/such/out.png"],
    );
    assert!(!ok);
    assert!(
        stderr.contains("output folder no/such does not exist"),
        "{stderr}"
    );
}

#[test]
fn info_explains_the_plan() {
    let (ok, _, tmp) = run_cli(Some(GOOD), &["info", "scene.ron"]);
    let dir = tmp.path();
    assert!(ok);
    let info = |set: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_glint"))
            .current_dir(dir)
            .args(["info", "scene.ron", "--set", set])
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let text = info("shadows=false");
    assert!(text.contains("skipped trace_shadow_rays"), "{text}");
    assert!(text.contains("shadows are off"), "{text}");
    assert!(text.contains("runs    build_triangle_bvh"), "{text}");
    assert!(text.contains("independent sampler"), "{text}");
    let text = info("sampler=sobol");
    assert!(text.contains("sobol sampler"), "{text}");
}

/// Runs the CLI in `dir` with the read end of standard output or error closed before it
/// writes, as `| head -1` or `2>&1 | head -1` leave it; returns the output it produced.
fn run_cli_closing(dir: &TempDir, args: &[&str], close_stdout: bool) -> std::process::Output {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Closing the read end now, before glint has loaded the scene, makes its write fail.
    if close_stdout {
        drop(child.stdout.take());
    } else {
        drop(child.stderr.take());
    }
    child.wait_with_output().unwrap()
}

/// `glint info scene.ron | head -1`: the reader closes the pipe before glint writes.
#[test]
fn a_closed_stdout_pipe_ends_the_cli_quietly() {
    let out = run_cli_closing(&scene_dir(GOOD), &["info", "scene.ron"], true);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "status {:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// A full disk under standard output is a failure, not a closed reader: status 1 and a
/// line saying so (Linux's `/dev/full` fails every write with "no space left").
#[test]
fn a_full_stdout_is_an_error() {
    let Ok(full) = std::fs::File::create("/dev/full") else {
        println!("skipping: no /dev/full here");
        return;
    };
    let dir = scene_dir(GOOD);
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(["info", "scene.ron"])
        .stdout(full)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with("error: cannot write to standard output"),
        "{stderr}"
    );
}

/// Standard error carries only diagnostics: with its reader gone, a render still writes
/// its image and `stress` its table, where `eprintln!` panicked (status 101) before.
#[test]
fn a_closed_stderr_pipe_loses_no_output() {
    // A scene without lights: its warning is written before the render starts.
    let unlit = GOOD.replace("PointLight((position: (0, 2, 2), color: (1, 1, 1))),", "");
    let dir = scene_dir(&unlit);
    let out = run_cli_closing(&dir, &["render", "scene.ron", "-o", "out.png"], false);
    assert_eq!(out.status.code(), Some(0), "{:?}", out.status);
    let img = image::open(dir.path().join("out.png")).unwrap();
    assert_eq!((img.width(), img.height()), (8, 8));

    let out = run_cli_closing(&dir, &["stress", "--case", "scale"], false);
    assert_eq!(out.status.code(), Some(0), "{:?}", out.status);
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("| pass |"), "{table}");

    // A failure stays a failure when its message cannot be read.
    let out = run_cli_closing(&dir, &["render", "missing.ron"], false);
    assert_eq!(out.status.code(), Some(1), "{:?}", out.status);
}

#[test]
fn the_cli_bounds_threads_and_reads_zero_as_all_cores() {
    let (ok, stderr, _dir) = run_cli(Some(GOOD), &["render", "scene.ron", "--threads", "100000"]);
    assert!(!ok);
    assert!(
        stderr.starts_with("error: --threads 100000 is more than 4 per core"),
        "{stderr}"
    );
    let (ok, stderr, dir) = run_cli(
        Some(GOOD),
        &["render", "scene.ron", "-o", "out.png", "--threads", "0"],
    );
    assert!(ok, "{stderr}");
    assert!(dir.path().join("out.png").exists());
}

#[test]
fn the_cli_refuses_an_output_it_cannot_write_before_rendering() {
    let (ok, stderr, dir) = run_cli(Some(GOOD), &["render", "scene.ron", "-o", "x.bmp"]);
    assert!(!ok && stderr.contains("unknown output format"), "{stderr}");
    assert!(!dir.path().join("x.bmp").exists());

    let dir = scene_dir(GOOD);
    std::fs::create_dir(dir.path().join("taken.png")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(["render", "scene.ron", "-o", "taken.png"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.starts_with("error: taken.png: is a folder, not an image file"),
        "{stderr}"
    );
    // The summary line is printed after a render: none ran.
    assert!(!stderr.contains("spp"), "{stderr}");
}

#[test]
fn the_cli_refuses_an_unwritable_output_folder_before_rendering() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scene_dir(GOOD);
    let mut locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    if tempfile::tempfile_in(&locked).is_ok() {
        // Root writes through permissions (as in CI): /proc refuses new files to anyone.
        locked = std::path::PathBuf::from("/proc");
    }
    assert!(
        tempfile::tempfile_in(&locked).is_err(),
        "no unwritable folder here"
    );
    let output = locked.join("out.png");
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(["render", "scene.ron", "-o", output.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains(&format!("cannot write in the folder {}", locked.display())),
        "{stderr}"
    );
}

/// Ctrl-C in the first pass: the unfinished image goes beside the output, which keeps
/// the complete image it held.
#[test]
fn an_interrupted_first_pass_does_not_replace_the_output() {
    // A first pass of many seconds: 1024x1024 pixels, 256 shadow rays each (about 8 s
    // on one core of the 2026 test machine; with 64 it took 2.0 s, too close to the
    // 1.5 s wait below for a faster machine).
    let scene = common::sphere_under_area_light(1024, "shadow_samples: 256");
    let dir = scene_dir(&scene);
    std::fs::write(dir.path().join("out.png"), b"previous").unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(["render", "scene.ron", "-o", "out.png", "--threads", "1"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert_eq!(
        std::fs::read(dir.path().join("out.png")).unwrap(),
        b"previous"
    );
    assert!(dir.path().join("out.partial.png").exists(), "{stderr}");
    assert!(stderr.contains("out.partial.png"), "{stderr}");
}

/// A scene whose material "m" has `kd_texture: Some(texture)`.
fn textured(texture: &str) -> String {
    GOOD.replace(
        r#""m": (kd: (0.5, 0.5, 0.5))"#,
        &format!(r#""m": (kd: (0.5, 0.5, 0.5), kd_texture: Some("{texture}"))"#),
    )
}

#[test]
fn texture_errors_name_the_material_and_the_field() {
    let dir = scene_dir(&textured("scene.ron"));
    let err = common::load_error_in(dir.path());
    assert!(
        err.contains("material \"m\": kd_texture: ") && err.contains("is not an image glint reads"),
        "{err}"
    );
    let dir = scene_dir(&textured("."));
    let err = common::load_error_in(dir.path());
    assert!(
        err.contains("material \"m\": kd_texture: ") && err.contains("is a folder"),
        "{err}"
    );

    // A corrupt PNG is found when the render decodes it; the error still names both.
    let (ok, stderr, _dir) = {
        let dir = scene_dir(&textured("bad.png"));
        std::fs::write(dir.path().join("bad.png"), b"\x89PNG\r\n\x1a\n cut short").unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_glint"))
            .current_dir(dir.path())
            .args(["render", "scene.ron", "-o", "out.png"])
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
            dir,
        )
    };
    assert!(!ok);
    assert!(
        stderr.starts_with("error: bad.png: material \"m\": kd_texture: cannot be decoded"),
        "{stderr}"
    );
}

#[test]
fn an_unknown_scene_extension_says_which_formats_are_read() {
    let dir = scene_dir(GOOD);
    std::fs::copy(dir.path().join("scene.ron"), dir.path().join("scene.ply")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(["info", "scene.ply"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.starts_with(
            "error: scene.ply: not a format glint reads (scenes: .ron; models: .gltf, .glb, .obj)"
        ),
        "{stderr}"
    );
}

#[test]
fn a_material_name_given_twice_is_an_error() {
    let twice = GOOD.replace(
        r#""m": (kd: (0.5, 0.5, 0.5))"#,
        r#""m": (kd: (0.5, 0.5, 0.5)), "m": (kd: (1, 0, 0))"#,
    );
    let err = load_error(&twice);
    assert!(err.contains("material \"m\" is defined twice"), "{err}");
}

#[test]
fn a_missing_model_file_names_the_entity_and_field() {
    let scene = GOOD.replace(
        r#"Sphere((name: Some("ball"), center: (0, 0, 0), radius: 1, material: "m")),"#,
        r#"Mesh((name: Some("model"), geometry: Gltf(path: "missing.glb"))),"#,
    );
    let dir = scene_dir(&scene);
    let err = common::load_error_in(dir.path());
    assert!(
        err.contains("entities[0] (Mesh \"model\"): geometry: file not found: "),
        "{err}"
    );
}

#[test]
fn a_scene_without_lights_or_geometry_is_warned_about() {
    let dark = GOOD.replace(
        r#"PointLight((position: (0, 2, 2), color: (1, 1, 1))),"#,
        "",
    );
    let warnings = load(&dark).warnings();
    assert!(
        warnings.iter().any(|w| w.contains("no lights")),
        "{warnings:?}"
    );
    let empty = r#"(camera: (position: (0, 0, 3), look_at: (0, 0, 0), fov_y: 40, width: 8, height: 8),
        entities: [PointLight((position: (0, 2, 2), color: (1, 1, 1)))])"#;
    let warnings = load(empty).warnings();
    assert!(
        warnings.iter().any(|w| w.contains("no geometry")),
        "{warnings:?}"
    );
    assert!(load(GOOD).warnings().is_empty());
}

#[test]
fn a_model_too_large_to_frame_blames_its_bounds_not_a_camera() {
    let dir = temp_dir();
    let obj = "v -3e38 -3e38 0\nv 3e38 -3e38 0\nv 0 3e38 0\nf 1 2 3\n";
    std::fs::write(dir.path().join("huge.obj"), obj).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .current_dir(dir.path())
        .args(["render", "huge.obj", "-o", "out.png"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("camera:"), "{stderr}");
    assert!(
        stderr.contains("huge.obj: bounds: the model spans") && stderr.contains("automatic camera"),
        "{stderr}"
    );
    assert!(!dir.path().join("out.png").exists());
}

/// Without the `view` feature, `glint view` is a known command that says how to get it.
#[cfg(not(feature = "view"))]
#[test]
fn the_cli_says_how_to_get_the_viewer_when_it_is_not_built_in() {
    let (ok, stderr, _) = run_cli(Some(GOOD), &["view", "scene.ron"]);
    assert!(!ok);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("--features view"), "{stderr}");
}
