//! Compiles tinybvh's BVH8_CPU (tinybvh/shim.cpp over the MIT-licensed,
//! header-only tinybvh/tiny_bvh.h) when the host is x86-64 with AVX2 and FMA
//! and a C++ compiler is found; otherwise the bench skips tinybvh's rows and
//! prints why (`cfg(tinybvh)` unset, the reason in `TINYBVH_SKIP`).
//! `GLINT_NO_TINYBVH=1` skips the C++ build (it takes tens of seconds).

fn main() {
    println!("cargo::rustc-check-cfg=cfg(tinybvh)");
    println!("cargo::rerun-if-changed=tinybvh/shim.cpp");
    println!("cargo::rerun-if-changed=tinybvh/tiny_bvh.h");
    println!("cargo::rerun-if-env-changed=GLINT_NO_TINYBVH");
    match build() {
        Ok(()) => println!("cargo::rustc-cfg=tinybvh"),
        Err(why) => println!("cargo::rustc-env=TINYBVH_SKIP={why}"),
    }
}

fn build() -> Result<(), String> {
    if std::env::var_os("GLINT_NO_TINYBVH").is_some() {
        return Err("GLINT_NO_TINYBVH is set".into());
    }
    host_has_avx2_fma()?;
    cc::Build::new()
        .cpp(true)
        .file("tinybvh/shim.cpp")
        .include("tinybvh")
        .std("c++20")
        .opt_level(3)
        .flag("-mavx2")
        .flag("-mfma")
        // Its builds of 50,000 triangles and more otherwise run on a job system of a
        // thread per core: the anchors' one-thread build row read 1.40 threads busy.
        .define("NO_THREADED_BUILDS", None)
        .warnings(false)
        .try_compile("glint_tinybvh")
        .map_err(|e| format!("the C++ shim did not compile: {e}"))
}

/// The build script runs on the host, which is also where the bench runs
/// unless cross-compiling (then the row is skipped).
fn host_has_avx2_fma() -> Result<(), String> {
    let (host, target) = (std::env::var("HOST"), std::env::var("TARGET"));
    if host != target {
        return Err("cross-compiling".into());
    }
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            return Ok(());
        }
        Err("the CPU lacks AVX2 or FMA, which BVH8_CPU needs".into())
    }
    #[cfg(not(target_arch = "x86_64"))]
    Err("BVH8_CPU needs x86-64 with AVX2 and FMA".into())
}
