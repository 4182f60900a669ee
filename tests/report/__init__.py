"""The work-precision report (`rbfmu report`) and the benchmark's reference (`rbfmu bench`)."""
