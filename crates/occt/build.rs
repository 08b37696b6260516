//! Compiles the C++ bridge (one file) against Debian's OpenCASCADE 7.6 and links the toolkits it uses.
//! `OCCT_INCLUDE_DIR` / `OCCT_LIB_DIR` point elsewhere than Debian's paths.

fn main() {
    let include = std::env::var("OCCT_INCLUDE_DIR").unwrap_or_else(|_| "/usr/include/opencascade".into());
    println!("cargo:rerun-if-changed=src/bridge.cpp");
    println!("cargo:rerun-if-changed=src/bridge.h");
    println!("cargo:rerun-if-env-changed=OCCT_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=OCCT_LIB_DIR");
    if !std::path::Path::new(&include)
        .join("STEPCAFControl_Reader.hxx")
        .exists()
    {
        panic!(
            "OpenCASCADE headers not found in {include}: run scripts/install-deps.sh (Debian: \
             libocct-data-exchange-dev, libocct-ocaf-dev), set OCCT_INCLUDE_DIR, or build without the \
             `occt` feature (--no-default-features)"
        );
    }
    cc::Build::new()
        .cpp(true)
        .file("src/bridge.cpp")
        .include(&include)
        .flag_if_supported("-std=c++17")
        .flag_if_supported("-w")
        .opt_level(2)
        .debug(false)
        .compile("hrtao_occt_bridge");
    if let Ok(dir) = std::env::var("OCCT_LIB_DIR") {
        println!("cargo:rustc-link-search=native={dir}");
    }
    for lib in [
        "TKXDESTEP",
        "TKXDEIGES",
        "TKSTEP",
        "TKIGES",
        "TKXSBase",
        "TKXCAF",
        "TKLCAF",
        "TKCDF",
        "TKMesh",
        "TKPrim",
        "TKTopAlgo",
        "TKBRep",
        "TKGeomBase",
        "TKG3d",
        "TKMath",
        "TKernel",
    ] {
        println!("cargo:rustc-link-lib=dylib={lib}");
    }
}
