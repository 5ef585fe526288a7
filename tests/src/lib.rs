//! Integration, conformance and compile-fail suites for the ULog workspace.
