#version 450 core
// Compiles (a stage may lack main until link), fails to link: no main() anywhere.
layout(local_size_x = 1) in;
void helper() {}
