"""The multi-interpretation image (DESIGN §4.8-4.9): posed faces, blocking boundaries, the vector
image, the thesis' grid and its windows."""
