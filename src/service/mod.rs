//! Service: HTTP routes → durable queue → store → worker threads, driving `analysis`.
//! The top of the flow; nothing in the physics core imports it.

/// `ashlar serve` arguments.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Address to listen on.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: String,
    /// Directory for the embedded job store and artifacts.
    #[arg(long, default_value = "./ashlar-data")]
    pub data: std::path::PathBuf,
}

/// Entry point of `ashlar serve` (blocks until shutdown). Provisional.
pub fn serve_cli(args: ServeArgs) -> Result<(), String> {
    Err(format!("serve is not implemented yet (addr {})", args.addr))
}
