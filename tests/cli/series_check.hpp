#pragma once
// Checking a series as ParaView would load it: every file the .pvd lists, read with VTK's own
// readers, holds the expected blocks with finite data.

#include "cli_run.hpp"

#include <gtest/gtest.h>

#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLMultiBlockDataReader.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace coro::test {

// Collects what VTK reports instead of printing it, so a reader's complaint fails the test.
class RecordingOutputWindow : public vtkOutputWindow {
public:
    static RecordingOutputWindow* New()
    {
        auto* window = new RecordingOutputWindow;
        window->InitializeObjectBase();
        return window;
    }
    void DisplayErrorText(const char* text) override { m_messages += text; }
    void DisplayWarningText(const char* text) override { m_messages += text; }
    std::string take()
    {
        std::string messages;
        messages.swap(m_messages);
        return messages;
    }

private:
    std::string m_messages;
};

// Loads every file the .pvd lists with VTK's readers; each must hold the blocks named in
// `bodies`, with points, cells and a finite displacement per point. Returns the count loaded.
inline int expect_every_listed_frame_loads(const std::filesystem::path& pvd, const std::vector<std::string>& bodies)
{
    vtkNew<RecordingOutputWindow> messages;
    vtkOutputWindow::SetInstance(messages);
    int loaded = 0;
    for (const std::string& frame : listed_frames(pvd)) {
        vtkNew<vtkXMLMultiBlockDataReader> reader;
        reader->SetFileName((pvd.parent_path() / frame).string().c_str());
        reader->Update();
        EXPECT_EQ(messages->take(), "") << frame << ": VTK reported errors while reading";
        auto* blocks = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutput());
        EXPECT_NE(blocks, nullptr) << frame;
        if (blocks == nullptr)
            continue;
        EXPECT_EQ(blocks->GetNumberOfBlocks(), bodies.size()) << frame;
        for (unsigned b = 0; b < blocks->GetNumberOfBlocks() && b < bodies.size(); ++b) {
            EXPECT_STREQ(blocks->GetMetaData(b)->Get(vtkCompositeDataSet::NAME()), bodies[b].c_str()) << frame;
            auto* grid = vtkUnstructuredGrid::SafeDownCast(blocks->GetBlock(b));
            EXPECT_NE(grid, nullptr) << frame << " block " << b;
            if (grid == nullptr)
                continue;
            EXPECT_GT(grid->GetNumberOfPoints(), 0) << frame;
            EXPECT_GT(grid->GetNumberOfCells(), 0) << frame;
            vtkDataArray* u = grid->GetPointData()->GetArray("displacement");
            EXPECT_NE(u, nullptr) << frame;
            if (u != nullptr) {
                EXPECT_EQ(u->GetNumberOfTuples(), grid->GetNumberOfPoints()) << frame;
                EXPECT_TRUE(std::isfinite(u->GetRange(-1)[1])) << frame;
            }
        }
        ++loaded;
    }
    vtkOutputWindow::SetInstance(nullptr);
    return loaded;
}

} // namespace coro::test
