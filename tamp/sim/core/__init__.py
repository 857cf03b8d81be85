"""What every Drake workcell shares: model data (`models`), the offline parser (`parsing`),
port messages (`messages`), the BT executor system (`executor`), the chunked runner
(`runner`), Meshcat views and recordings (`recording`), seeded perturbations
(`perturbation`), run causes (`outcome`) and RGB-D cameras with seeded depth noise (`camera`)."""
