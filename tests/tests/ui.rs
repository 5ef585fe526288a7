//! Compile-time misuse of `#[derive(ULog)]`, one rule per file in `ui/fail` with the expected
//! compiler output beside it (refresh with `TRYBUILD=overwrite`), and cases that must compile
//! in `ui/pass`.

#[test]
fn derive_ui() {
    let t = trybuild::TestCases::new();
    t.compile_fail("ui/fail/*.rs");
    t.pass("ui/pass/*.rs");
}
