// main.cpp — `ambience`: parse the command line, run one subcommand, map errors to exit codes.
//   0  success
//   2  bad input (unknown option, missing or malformed file, absurd value): one line on stderr
//   1  an internal failure (a bug or an unavailable platform)
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "app/Commands.h"
#include "world/Error.h"

int main(int argc, char** argv) {
    CLI::App app{"Ambience: procedural open-world terrain with a dynamic ambience volume"};
    app.name("ambience");
    app.require_subcommand(1);
    amb::addRunCommand(app);
    amb::addViewCommand(app);
    amb::addProbeCommand(app);
    amb::addWorldCommand(app);
    amb::addReplayCommand(app);
    amb::addShCommand(app);

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "ambience: error: %s (see 'ambience --help')\n", e.what());
        return 2;
    } catch (const amb::InputError& e) {
        std::fprintf(stderr, "ambience: error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ambience: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
