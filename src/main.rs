//! The `prgenuav` command line: parses arguments, runs a subcommand, maps the outcome to an exit code.
fn main() {
    println!("prgenuav");
}
