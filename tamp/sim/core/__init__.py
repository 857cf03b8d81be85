"""What every Drake workcell shares: model data (`models`), the offline parser (`parsing`),
the SAP plant (`plant`), port messages (`messages`: skills and views), the BT executor system
(`executor`), the chunked runner (`runner`), Meshcat views and recordings (`recording`), run
causes (`outcome`), RGB-D cameras with seeded depth noise (`camera`), the label-image detector
(`perception`), the timing of a run's parts (`timing`) and torch's thread count for
networks called inside a step (`threads`). It ranks below the cells: nothing
here imports ``tamp.sim.smp``, ``tamp.sim.lots`` or ``tamp.sim.refine``; what is a cell's own
(its object classes, its workspaces) is passed in."""
