fn main() -> std::process::ExitCode {
    mbgc::cli::main()
}
