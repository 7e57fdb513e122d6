fn main() -> std::process::ExitCode {
    mbgc_cli::main()
}
