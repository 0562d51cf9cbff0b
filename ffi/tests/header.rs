//! The committed C header `include/ldcbf.h` is what cbindgen generates from
//! `src/lib.rs` (and the modules it declares: `src/types.rs`, `src/checks.rs`)
//! now. `LDCBF_BLESS=1 cargo test -p ldcbf-ffi --test header`
//! rewrites it.

use std::path::Path;

#[test]
fn committed_header_is_up_to_date() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml"))
        .expect("ffi/cbindgen.toml parses");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        // The crate's root file, parsed directly (cbindgen follows its `mod`
        // items to `types.rs` and `checks.rs`): no nested `cargo metadata`.
        .with_src(crate_dir.join("src/lib.rs"))
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("the header is UTF-8");
    let path = crate_dir.join("include/ldcbf.h");
    if std::env::var_os("LDCBF_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write include/ldcbf.h");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "ffi/include/ldcbf.h differs from what cbindgen generates from ffi/src/lib.rs; \
         regenerate it with `LDCBF_BLESS=1 cargo test -p ldcbf-ffi --test header` and commit it"
    );
}
