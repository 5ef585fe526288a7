//! `ulog`: the command-line tool ([`ulog_runtime::cli`]).

fn main() -> std::process::ExitCode {
    ulog_runtime::cli::handle_signals();
    std::process::ExitCode::from(ulog_runtime::cli::main(std::env::args_os()))
}
