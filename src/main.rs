fn main() {
    std::process::exit(cgnodes::cli::main_with(cgnodes::nodes::builtin_registry()));
}
