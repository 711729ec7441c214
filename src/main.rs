//! The `tdvass` command line; see [`tdvass::cli`].

fn main() -> std::process::ExitCode {
    tdvass::cli::main_entry()
}
