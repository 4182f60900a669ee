"""Where the FMU runs: binaries for each platform, the source FMU, another co-simulation master."""
