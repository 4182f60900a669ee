"""Controller laws in CasADi, their files and their FMI variables: sampled-data controllers built into FMUs like scenes."""
