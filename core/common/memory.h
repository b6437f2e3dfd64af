#pragma once
// The process's memory as the operating system counts it: the peak a job reports, and
// handing freed heap back so that the next stage's peak starts from what is in use.

namespace satmesh {

// The process's peak resident set so far, MB (getrusage's ru_maxrss).
double PeakRssMb();

// Returns the heap's free pages to the operating system (glibc's malloc_trim; nothing
// elsewhere). glibc keeps a freed block of a few MB or more on its heap once blocks that
// large have been freed (its mmap threshold rises), so a stage's peak counted the previous
// stage's freed workspaces too. Stereo 0.5 m s1: after the level (its views and buffers
// freed) 352 -> 215-230 MB, level 0's own plateau (after the start's remeshing) 343 -> 325 MB.
void ReturnFreedMemory();

}  // namespace satmesh
