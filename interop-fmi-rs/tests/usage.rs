//! The command line of interop-fmi-rs. This integration test also makes
//! `cargo test --workspace [--release]` build the executable itself, with the
//! workspace's feature set, which tests/interop/test_fmi_rs.py then runs
//! (a separate `cargo build -p interop-fmi-rs` would resolve features
//! differently and rebuild part of the `fmi` crate's dependencies).

use std::process::Command;

const EXE: &str = env!("CARGO_BIN_EXE_interop-fmi-rs");

#[test]
fn without_arguments_it_prints_the_usage() {
    let out = Command::new(EXE).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("usage: interop-fmi-rs FMU"));
}

#[test]
fn a_missing_fmu_is_an_error_not_a_panic() {
    let out = Command::new(EXE)
        .args(["/nonexistent/tdvass.fmu", "{}", "/nonexistent/out.csv"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.starts_with("interop-fmi-rs: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
