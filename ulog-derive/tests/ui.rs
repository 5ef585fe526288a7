//! Compile-time misuse of `#[derive(ULog)]`, one rule per file in `tests/ui/fail` with the expected
//! compiler output beside it (refresh with `TRYBUILD=overwrite`), and cases that must compile
//! in `tests/ui/pass`.

#[test]
fn derive_ui() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/fail/*.rs");
    t.pass("tests/ui/pass/*.rs");
}
