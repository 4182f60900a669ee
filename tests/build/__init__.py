"""The build: archives, what a scene file puts into them, their documentation, licence and generated code."""
