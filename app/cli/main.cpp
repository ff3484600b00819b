// main.cpp — `ambience`: parse the command line, run one subcommand, map errors to exit codes.
//   0  success
//   2  bad input (unknown option, missing or malformed file, absurd value): one line on stderr
//   1  an internal failure (a bug or an unavailable platform)
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>

#include "app/cli/Commands.h"
#include "world/Error.h"

int main(int argc, char** argv) {
    CLI::App app{"Ambience: procedural open-world terrain with a dynamic ambience volume"};
    app.name("ambience");
    // At most one subcommand; none is reported after parsing, so that an unknown option or
    // subcommand is named in the error rather than hidden behind "a subcommand is required".
    app.require_subcommand(0, 1);
    amb::addRunCommand(app);
    amb::addViewCommand(app);
    amb::addProbeCommand(app);
    amb::addWorldCommand(app);
    amb::addReplayCommand(app);
    amb::addShCommand(app);
    amb::addBenchCommand(app);
    amb::addCompareCommand(app);
    amb::addSettingsCommand(app);
    amb::addTuneCommand(app);

    // An unknown subcommand is an error even with --help (CLI11 would print the parent's help
    // and exit 0): walk the leading words down the subcommand tree first.
    {
        CLI::App* level = &app;
        for (int i = 1; i < argc; ++i) {
            const std::string word = argv[i];
            if (word.empty() || word[0] == '-') break;
            const auto subs = level->get_subcommands([](CLI::App*) { return true; });
            if (subs.empty()) break;
            CLI::App* next = nullptr;
            for (CLI::App* sub : subs)
                if (sub->check_name(word)) next = sub;
            if (!next) {
                std::fprintf(stderr, "ambience: error: unknown subcommand '%s' of '%s' (see '%s --help')\n",
                             word.c_str(), level->get_name().c_str(),
                             level == &app ? "ambience" : ("ambience " + level->get_name()).c_str());
                return 2;
            }
            level = next;
        }
    }

    try {
        app.parse(argc, argv);
        if (app.get_subcommands().empty()) {
            std::fprintf(stderr, "ambience: error: a subcommand is required (see 'ambience --help')\n");
            return 2;
        }
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
    } catch (const amb::RunFailure& e) {
        std::fprintf(stderr, "ambience: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ambience: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
