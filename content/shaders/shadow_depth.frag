// Depth only: colour writes are off; the rasteriser writes depth (with glPolygonOffset bias).
void main() {}
