#pragma once
uint helper_mul(uint a, uint b) { return a * b; }
