#version 450
// The tree's silhouette in one colour.
layout(location = 0) out vec4 color;
void main() { color = vec4(0.2, 0.45, 0.1, 1.0); }
