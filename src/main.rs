fn main() {
    std::process::exit(cgnodes::cli::main_with(
        cgnodes::registry::Registry::builtin(),
    ));
}
