"""Plain helpers every layer uses: validation of user input, planar vectors, the spatial grid,
k-nearest neighbours, the thread policy."""
