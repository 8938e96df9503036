// The stepwise command line as a call: the arguments parsed (CLI11), the command run, its exit status returned (0,
// 1 failed or diverged, 2 bad input, each with its one line). app/main.cpp calls it inside the process's MPI session
// and signal handling; a test calls it as a user would type the command.
#pragma once

namespace stepwise {

// nothing escapes: bad input (the commands' InputError, a path the file system refuses) is 2, anything else 1
int command_line(int argc, char** argv);

}  // namespace stepwise
