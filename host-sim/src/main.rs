//! `edgekf`: simulate, estimate, close the loop and report on the host; every command comes
//! from the systems' registry.

fn main() -> std::process::ExitCode {
    edgekf_sim::cli::main(edgekf_sim::systems::REGISTRY)
}
