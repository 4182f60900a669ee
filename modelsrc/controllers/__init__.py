"""Controller laws in CasADi, their files and FMI variables: sampled-data controllers built into FMUs like scenes."""
