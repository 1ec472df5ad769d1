// vdbclay: the command-line front end. Parses the command line with CLI11, runs one subcommand, and
// turns every failure into one "vdbclay: error: ..." line on stderr and a non-zero exit code:
// 2 for a wrong command line, 1 for a command that ran and failed.
#include "Cli.h"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <exception>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <iostream>
#include <memory>
#include <new>

#ifndef VDBCLAY_VERSION
#define VDBCLAY_VERSION "unknown"
#endif

namespace {

using namespace vdbclay::cli;

constexpr const char* kCommandList =
    "new, sculpt, edit, mesh, render, info, import, export, export-levelset, lod, synth, diff, tool, index, query, demo, bench or selftest";

int run(int argc, char** argv)
{
    CLI::App app{"VDBClay: sparse volume sculpting on OpenVDB (Hermite data, materials, CSG brushes).", "vdbclay"};
    app.set_version_flag("--version", std::string("vdbclay ") + VDBCLAY_VERSION);
    app.require_subcommand(1);

    int threads = 0;
    NewOptions newOptions;
    SculptOptions sculptOptions;
    MeshCommandOptions meshOptions;
    InfoOptions infoOptions;
    DemoOptions demoOptions;
    BenchCommandOptions benchOptions;
    SelftestOptions selftestOptions;
    ImportOptions importOptions;
    ExportOptions exportOptions;
    ExportLevelSetOptions exportLevelSetOptions;
    LodOptions lodOptions;
    SynthCommandOptions synthOptions;
    DiffOptions diffOptions;
    ToolMakeOptions toolOptions;
    RenderOptions renderOptions;
    EditOptions editOptions;
    IndexOptions indexOptions;
    QueryOptions queryOptions;

    CLI::App* newCmd = addNewCommand(app, newOptions);
    CLI::App* sculptCmd = addSculptCommand(app, sculptOptions);
    CLI::App* meshCmd = addMeshCommand(app, meshOptions);
    CLI::App* renderCmd = addRenderCommand(app, renderOptions);
    CLI::App* editCmd = addEditCommand(app, editOptions);
    CLI::App* infoCmd = addInfoCommand(app, infoOptions);
    CLI::App* demoCmd = addDemoCommand(app, demoOptions);
    CLI::App* benchCmd = addBenchCommand(app, benchOptions);
    CLI::App* selftestCmd = addSelftestCommand(app, selftestOptions);
    CLI::App* importCmd = addImportCommand(app, importOptions);
    CLI::App* exportCmd = addExportCommand(app, exportOptions);
    CLI::App* exportLevelSetCmd = addExportLevelSetCommand(app, exportLevelSetOptions);
    const LodCommands lodCmds = addLodCommand(app, lodOptions);
    CLI::App* synthCmd = addSynthCommand(app, synthOptions);
    CLI::App* diffCmd = addDiffCommand(app, diffOptions);
    const ToolCommands toolCmds = addToolCommand(app, toolOptions);
    const IndexCommands indexCmds = addIndexCommand(app, indexOptions);
    CLI::App* queryCmd = addQueryCommand(app, queryOptions);
    for (CLI::App* cmd : {newCmd, sculptCmd, editCmd, meshCmd, renderCmd, demoCmd, benchCmd, importCmd, exportCmd, lodCmds.build, lodCmds.inspect, synthCmd, toolCmds.make}) addThreadsOption(*cmd, threads);
    // Set after the subcommands exist: CLI11 copies the parent's footer into subcommands created later.
    app.footer("Run 'vdbclay COMMAND --help' for the options of one command.\n"
               "Exit codes: 0 success, 1 the command failed, 2 wrong command line.");

    // CLI11 answers --help before it looks at the command: "vdbclay NOSUCHCOMMAND --help" printed the
    // general help and exited 0, as if the command existed.
    if (argc > 1 && argv[1][0] != '-') {
        bool known = false;
        for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) known = known || sub->check_name(argv[1]);
        if (!known) {
            printError(std::string("unknown command '") + argv[1] + "' (expected " + kCommandList + "; see 'vdbclay --help')");
            return kExitUsage;
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-') {
            printError(std::string("unknown command '") + argv[1] + "' (expected " + kCommandList + "; see 'vdbclay --help')");
            return kExitUsage;
        }
        std::string hint = "vdbclay --help";
        for (CLI::App* sub : app.get_subcommands()) {
            hint = "vdbclay " + sub->get_name();
            for (CLI::App* leaf : sub->get_subcommands()) hint += " " + leaf->get_name();
            hint += " --help";
        }
        printError(std::string(e.what()) + " (see '" + hint + "')");
        return kExitUsage;
    }

    std::unique_ptr<tbb::global_control> threadLimit;
    if (threads > 0) {
        threadLimit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                            static_cast<std::size_t>(threads));
    }

    if (*newCmd) return runNew(newOptions);
    if (*sculptCmd) return runSculpt(sculptOptions);
    if (*meshCmd) return runMesh(meshOptions);
    if (*renderCmd) return runRender(renderOptions);
    if (*editCmd) return runEdit(editOptions);
    if (*infoCmd) return runInfo(infoOptions);
    if (*demoCmd) return runDemo(demoOptions);
    if (*benchCmd) return runBenchCommand(benchOptions);
    if (*selftestCmd) return runSelftest(selftestOptions);
    if (*importCmd) return runImport(importOptions);
    if (*exportCmd) return runExport(exportOptions);
    if (*exportLevelSetCmd) return runExportLevelSet(exportLevelSetOptions);
    if (*lodCmds.build) return runLodBuild(lodOptions);
    if (*lodCmds.info) return runLodInfo(lodOptions);
    if (*lodCmds.inspect) return runLodInspect(lodOptions);
    if (*synthCmd) return runSynth(synthOptions);
    if (*diffCmd) return runDiff(diffOptions);
    if (*toolCmds.make) return runToolMake(toolOptions);
    if (*indexCmds.add) return runIndexAdd(indexOptions);
    if (*indexCmds.info) return runIndexInfo(indexOptions);
    if (*indexCmds.remove) return runIndexRemove(indexOptions);
    if (*queryCmd) return runQuery(queryOptions);
    printError("no command given (see 'vdbclay --help')");
    return kExitUsage;
}

/// Edits, re-meshing and undo allocate and free buffers of megabytes many times a second. By default
/// glibc maps each of those afresh and unmaps it on free, and every page of a fresh mapping faults on
/// its first touch: on the 2-core VMs we measure on, that was a third of a reshaping brush's time (a
/// 7 MB copy took 25 ms). Served from the heap, and up to 64 MB of freed heap kept, they reuse pages
/// already mapped (bench editor: smooth steps 496 -> 315 ms, flatten 871 -> 578 ms).
void keepLargeBuffersMapped()
{
#ifdef __GLIBC__
    mallopt(M_MMAP_THRESHOLD, 32 << 20); // glibc's largest
    mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
}

} // namespace

int main(int argc, char** argv)
{
    keepLargeBuffersMapped();
    try {
        return run(argc, argv);
    } catch (const UsageError& e) {
        printError(e.what());
        return kExitUsage;
    } catch (const vdbclay::OutputRefused& e) {
        printError(e.what());
        return kExitUsage;
    } catch (const std::bad_alloc&) {
        printError("out of memory");
        return kExitFailure;
    } catch (const std::exception& e) {
        printError(e.what());
        return kExitFailure;
    } catch (...) {
        printError("unexpected internal failure");
        return kExitFailure;
    }
}
