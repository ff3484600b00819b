#version 450 core
// shadow_caster.frag — depth only: the shadow pass writes no colour.
void main() {}
